"""The waviness of the measured helix traces: the marks a vibration leaves along the face.

A gear measuring machine's helix trace of a flank that chattered shows a regular wave riding on the lead: each
space's flank at height z is finished when a cutter tooth passes it, once per work revolution, while the carriage
moves the axial feed s, so the flank samples the tool's vibration (frequency f) once per visit and shows it at the
visits' beat: f T mod 1 cycles per s of face (T the interval between a space's visits), a wavelength along the face
of s / |f T - round(f T)| (virtual_machine/processes/skiving/machine_effect.py: ``surface_wavelength``). The feed
marks themselves (one per s) are that formula at a vibration synchronous with the visits.

:func:`helix_waviness` finds the dominant wave of a gear's helix traces: each trace (tooth, flank) with its best-fit
line taken out (the slope is f_Hbeta's), Hann-windowed and zero-padded; the amplitude spectra averaged over the
traces (the teeth are visited at different phases of the vibration, so their waves do not add in phase); the peak
between two sample steps and half the evaluation range, the feed marks' own wavelengths left out.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

UM = 1e3


def helix_waviness(
    z_mm: np.ndarray, traces: Mapping[str, np.ndarray], feed: float | None = None, longest: float | None = None
) -> dict | None:
    """The dominant wave of the helix traces: ``z_mm`` (n,) the heights [mm], ``traces`` per flank (teeth, n) the
    deviations [mm] (NaN where the probe found no flank: that trace is left out). ``feed``: the axial feed per work
    revolution [mm], whose marks (the cusps every s, and their harmonics) are left out of the search (within the
    window's main lobe, 2 / the range, of each); ``longest``: the longest wavelength looked for [mm] (default half
    the evaluation range). Returns its wavelength [mm] and its amplitude (half the peak-to-peak of a sine) [um], and
    the mean peak-to-peak of the traces about their lines [um]; None when no trace holds four points."""
    z = np.asarray(z_mm, dtype=float)
    rows = [np.asarray(r, dtype=float) for t in traces.values() for r in np.atleast_2d(t)]
    rows = [r for r in rows if np.isfinite(r).all()]
    if len(z) < 4 or not rows:
        return None
    a = np.array([r - np.polyval(np.polyfit(z, r, 1), z) for r in rows]) * UM
    n = len(z)
    pad = 8 * n  # a finer grid of wavelengths to read the peak from
    window = np.hanning(n)
    spectrum = np.abs(np.fft.rfft(a * window, n=pad, axis=1)).mean(axis=0) * 2 / window.sum()
    freq = np.fft.rfftfreq(pad, (z[-1] - z[0]) / (n - 1))  # cycles per mm
    span = z[-1] - z[0]
    lo = 1.0 / (longest if longest is not None else span / 2)
    hi = 0.5 * (n - 1) / span  # two samples a wave
    band = (freq >= lo) & (freq <= hi)
    if feed:  # the feed marks: a vibration synchronous with the visits
        band &= np.abs(freq * feed - np.round(freq * feed)) * (1 / feed) > 2 / span
    if not band.any():
        return None
    i = int(np.flatnonzero(band)[np.argmax(spectrum[band])])
    return {
        "wavelength_mm": float(1.0 / freq[i]),
        "amplitude_um": float(spectrum[i]),
        "peak_to_peak_um": float(np.ptp(a, axis=1).mean()),
    }
