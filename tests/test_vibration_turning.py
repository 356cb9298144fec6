"""Vibration turning (seed 004): the feed vibration's forms, the crests of the turned surface from the exact
envelope against the prediction from the path positions (0.05 um) and against the manifold3d solid (the mesh
tolerance + 0.5 um), the seed's statements on symmetric (Delta_max > 2 S0 raises the crests) and asymmetric
vibration (xi = T_in / T_out != 1 lowers them, where it does and where it does not), chip breaking, bad inputs.

Tolerances: envelope against the exact crest or the prediction 0.05 um (measured ~2e-5 um); manifold solid against
the envelope 1 um (its stated chord tolerance) + 0.5 um (measured <= 0.14 um)."""

from __future__ import annotations

import dataclasses
import math

import manifold3d as mf
import numpy as np
import pytest

from cutting.turning.vibration import (
    FeedVibration,
    TurningSetup,
    crest_height,
    cut_workpiece,
    uncut_thickness,
)
from metrology.turned_surface import crest_heights, roughness, solid_crests

UM = 1e-3  # mm
S0, R_EPS, DEPTH = 0.2, 0.8, 0.3
PLAIN = TurningSetup(20.0, S0, R_EPS, DEPTH)
H_S0 = R_EPS - math.sqrt(R_EPS**2 - S0**2 / 4)  # 6.2746 um; the textbook S0^2 / 8 r_eps = 6.25 um to second order
H_2S0 = R_EPS - math.sqrt(R_EPS**2 - S0**2)  # 25.40 um
#: a quarter cycle's phase shift a turn, A = S0: symmetric Delta_max = S0 + 2A sin(pi/4) = 2.41 S0
F, A = 2.25, 0.2
ENVELOPE_TOL = 0.05 * UM
MESH_TOL = 1.0 * UM


def vib(amplitude: float = A, f: float = F, xi: float = 1.0, form: str = "soft") -> TurningSetup:
    return dataclasses.replace(PLAIN, vibration=FeedVibration(amplitude, f, xi, form))


SYMMETRIC = vib()
ASYM_SOFT = vib(xi=3.0)
ASYM_HARD = vib(xi=3.0, form="hard")
PHIS = (0.1234, 1.7, 3.3, 5.9)


@pytest.fixture(scope="module")
def rough() -> dict[str, object]:
    return {
        name: roughness(s, 72)
        for name, s in {
            "plain": PLAIN,
            "symmetric": SYMMETRIC,
            "symmetric hard": vib(form="hard"),
            "soft": ASYM_SOFT,
            "hard": ASYM_HARD,
        }.items()
    }


# --- the vibration --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("form", ["soft", "hard"])
@pytest.mark.parametrize("xi", [1.0, 3.0, 0.25])
def test_vibration_has_zero_mean_spans_plus_minus_a_and_moves_with_the_feed_for_t_in(form: str, xi: float):
    v = FeedVibration(0.1, 1.5, xi, form)
    period = 2 * math.pi / v.cycles_per_rev
    theta = np.linspace(0.0, period, 200001)[:-1] + 7 * period  # one whole cycle, seven cycles on
    a = v.axial(theta)
    assert abs(a.mean()) < 1e-9
    assert a.min() == pytest.approx(-0.1, abs=1e-8) and a.max() == pytest.approx(0.1, abs=1e-8)
    rising = np.diff(a) > 0
    assert rising.mean() == pytest.approx(xi / (1 + xi), abs=1e-4)  # T_in / (T_in + T_out)


def test_symmetric_forms_are_the_cosine_and_the_triangle():
    theta = np.linspace(0.0, 20.0, 1001)
    assert np.allclose(FeedVibration(0.1, 1.5).axial(theta), -0.1 * np.cos(1.5 * theta), atol=1e-12)
    u = np.mod(1.5 * theta / (2 * math.pi), 1.0)
    assert np.allclose(FeedVibration(0.1, 1.5, 1.0, "hard").axial(theta), 0.1 * (1 - 4 * np.abs(u - 0.5)), atol=1e-12)


def test_spacing_of_successive_turns_follows_the_phase_shift():
    """Symmetric: Delta = S0 + 2A sin(pi frac f) sin(...): from S0 - 2A sin(pi/4) to Delta_max = 2.41 S0 > 2 S0."""
    lo, hi = SYMMETRIC.spacing_range()
    d = 2 * A * math.sin(math.pi * 0.25)
    assert lo == pytest.approx(S0 - d, abs=1e-7) and hi == pytest.approx(S0 + d, abs=1e-7)
    assert hi > 2 * S0 and lo < 0
    assert ASYM_HARD.spacing_range() == pytest.approx((S0 - 2 * A, S0 + 2 * A / 3), abs=1e-6)
    assert PLAIN.spacing_range() == (S0, S0)


# --- the crests -----------------------------------------------------------------------------------------------


def test_plain_turning_crest_is_the_exact_formula():
    for phi in PHIS:
        c = crest_heights(PLAIN.surface(phi))
        assert len(c.height) >= 10
        assert np.max(np.abs(c.height - H_S0)) < ENVELOPE_TOL
        assert np.allclose(c.spacing, S0, atol=1e-6)
        assert np.allclose(PLAIN.predicted_crests(phi).height, H_S0, atol=1e-12)
    assert crest_height(S0, R_EPS, DEPTH) == pytest.approx(S0**2 / (8 * R_EPS), abs=0.03 * UM)


@pytest.mark.parametrize("setup", [SYMMETRIC, ASYM_SOFT, ASYM_HARD, vib(f=1.5)], ids=["sym", "soft", "hard", "f1.5"])
def test_envelope_matches_the_prediction_from_the_path_positions(setup: TurningSetup):
    for phi in PHIS:
        e, p = crest_heights(setup.surface(phi)), setup.predicted_crests(phi)
        assert len(e.z) == len(p.z) >= 5
        assert np.max(np.abs(e.z - p.z)) < 1e-5  # midway between two neighbouring paths (10 nm: flat crests)
        assert np.max(np.abs(e.height - p.height)) < ENVELOPE_TOL
        assert np.allclose(e.gap, p.gap, atol=2e-4)  # valleys on the 0.1 um grid


def test_symmetric_vibration_with_delta_max_over_2s0_raises_the_crests(rough):
    plain, sym = rough["plain"], rough["symmetric"]
    assert plain.rt_max == pytest.approx(H_S0, abs=ENVELOPE_TOL)
    assert sym.rt_max > 5 * plain.rt_max  # 37.1 against 6.27 um
    assert sym.crest_mean > 1.5 * plain.crest_mean  # 12.1 um
    assert sym.rt_max <= crest_height(SYMMETRIC.spacing_range()[1], R_EPS, DEPTH) + ENVELOPE_TOL
    assert np.max(np.abs(sym.rt - roughness(SYMMETRIC, 72, predicted=True).rt)) < ENVELOPE_TOL


def test_asymmetric_vibration_lowers_the_crests_when_it_leads_the_phase_shift(rough):
    """f = 2.25, A = 0.2 mm, xi = 3: Rt_max 37.1 -> 25.3 (soft), 17.6 um (hard); mean crest 12.1 -> 9.2, 8.2 um;
    the hard form against its own symmetric (triangle) form too; every one still breaks the chip."""
    sym = rough["symmetric"]
    for name in ("soft", "hard"):
        r = rough[name]
        assert r.rt_max < sym.rt_max - 5 * UM
        assert r.rt_mean < sym.rt_mean and r.crest_mean < sym.crest_mean
        assert r.rt_max > 2 * rough["plain"].rt_max  # still rougher than plain turning
    assert rough["hard"].rt_max < rough["symmetric hard"].rt_max - 5 * UM
    assert rough["hard"].crest_mean < rough["symmetric hard"].crest_mean
    assert rough["hard"].rt_max == pytest.approx(crest_height(S0 + 2 * A / 3, R_EPS, DEPTH), abs=ENVELOPE_TOL)
    for setup in (SYMMETRIC, ASYM_SOFT, ASYM_HARD):
        assert setup.chip_breaks(26).per_rev == F


def test_where_asymmetry_does_not_lower_the_crests():
    """Against the phase shift (xi = 1/3 at f = 2.25) it raises them; leading it is necessary, not sufficient: at
    f = 2.45 the hard xi = 3 form leaves Rt_max 19.0 um against 16.2 um of the symmetric hard form; at f = n + 1/2
    the paths two turns apart are 2 S0 apart, so where the chip breaks (Delta = 0) the crest is h(2 S0) whatever
    the form."""
    against = roughness(vib(xi=1 / 3), 36, predicted=True)
    assert against.rt_max > roughness(SYMMETRIC, 36, predicted=True).rt_max + 10 * UM
    leading = roughness(vib(f=2.45, xi=3.0, form="hard"), 72).rt_max
    assert leading == pytest.approx(19.0 * UM, abs=0.1 * UM)
    assert leading > roughness(vib(f=2.45, form="hard"), 72).rt_max + 2 * UM  # 16.2 um
    for setup in (vib(f=1.5), vib(f=1.5, xi=3.0, form="hard")):
        breaks = setup.chip_breaks(8)
        assert len(breaks.angles) > 0
        phi = float(np.mod(breaks.angles[-1], 2 * math.pi))
        assert crest_heights(setup.surface(phi)).rt == pytest.approx(H_2S0, abs=ENVELOPE_TOL)


def test_integer_cycles_per_rev_turns_like_plain_turning():
    setup = vib(f=2.0)
    assert setup.spacing_range() == pytest.approx((S0, S0), abs=1e-12)
    assert np.allclose(crest_heights(setup.surface(0.7)).height, H_S0, atol=ENVELOPE_TOL)
    assert len(setup.chip_breaks(8).angles) == 0


# --- chip breaking --------------------------------------------------------------------------------------------


def test_plain_turning_never_breaks_the_chip():
    b = PLAIN.chip_breaks(10)
    assert len(b.angles) == 0 and b.per_rev == 0.0
    assert b.min_thickness == pytest.approx(S0, abs=1e-12)


def test_vibration_breaks_the_chip_once_a_cycle():
    b = SYMMETRIC.chip_breaks(26)
    assert b.per_rev == F  # 54 breaks over the 24 counted turns
    assert np.allclose(np.diff(b.angles), 2 * math.pi / F, atol=1e-9)
    assert np.max(np.abs(uncut_thickness(SYMMETRIC, b.angles))) < 1e-9
    assert b.min_thickness < 0  # the tool runs behind the surface the earlier turns left: air cutting
    prev = SYMMETRIC.chip_breaks(26, previous_only=True)
    assert prev.per_rev == F


@pytest.mark.parametrize(("f", "threshold"), [(1.5, S0 / 2), (2.25, S0 / (2 * math.sin(math.pi / 4)))])
def test_chip_breaks_once_the_amplitude_suffices(f: float, threshold: float):
    """Symmetric: Delta_min = S0 - 2A sin(pi frac f) reaches 0 at A = threshold."""
    assert len(vib(0.97 * threshold, f).chip_breaks(10).angles) == 0
    assert vib(1.03 * threshold, f).chip_breaks(10 if f == 1.5 else 14).per_rev == f


# --- bad inputs -----------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"amplitude": -0.1}, "amplitude"),
        ({"amplitude": math.nan}, "amplitude"),
        ({"cycles_per_rev": 0.0}, "cycles_per_rev"),
        ({"xi": 0.0}, "xi"),
        ({"xi": -2.0}, "xi"),
        ({"form": "square"}, "form"),
    ],
)
def test_bad_vibration_is_refused_naming_the_field(kwargs: dict, field: str):
    args = {"amplitude": 0.1, "cycles_per_rev": 1.5, "xi": 1.0, "form": "soft"} | kwargs
    with pytest.raises(ValueError, match=field):
        FeedVibration(**args)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"radius": 0.0}, "radius"),
        ({"feed": -0.1}, "feed"),
        ({"feed": math.inf}, "feed"),
        ({"nose_radius": 0.0}, "nose_radius"),
        ({"depth": 0.0}, "depth"),
        ({"depth": 0.9}, "depth"),
        ({"vibration": 0.1}, "vibration"),
    ],
)
def test_bad_setup_is_refused_naming_the_field(kwargs: dict, field: str):
    args = {"radius": 20.0, "feed": S0, "nose_radius": R_EPS, "depth": DEPTH} | kwargs
    with pytest.raises(ValueError, match=field):
        TurningSetup(**args)


def test_bad_calls_are_refused_naming_the_argument():
    with pytest.raises(ValueError, match="n_revs"):
        crest_heights(SYMMETRIC.surface(0.1, n_revs=6))
    with pytest.raises(ValueError, match="n_revs"):
        PLAIN.chip_breaks(2)
    with pytest.raises(ValueError, match="n_phi"):
        roughness(PLAIN, 0)
    with pytest.raises(ValueError, match="method"):
        cut_workpiece(PLAIN, 8, method="voxel")
    with pytest.raises(ValueError, match="tolerance"):
        cut_workpiece(PLAIN, 8, tolerance=0.0)


# --- the manifold3d solid -------------------------------------------------------------------------------------

SMALL = TurningSetup(3.0, S0, R_EPS, 0.2)  # a 6 mm bar, 1.6 to 4 mm long: a few seconds


@pytest.fixture(scope="module")
def solids() -> dict[str, object]:
    return {
        "hull": cut_workpiece(SMALL, 8, MESH_TOL, method="hull"),
        "loft": cut_workpiece(SMALL, 20, MESH_TOL, method="loft"),
        "symmetric": cut_workpiece(dataclasses.replace(SMALL, vibration=FeedVibration(A, F)), 16, MESH_TOL),
        "hard": cut_workpiece(dataclasses.replace(SMALL, vibration=FeedVibration(A, F, 3.0, "hard")), 16, MESH_TOL),
    }


def _pairs(a, b, floor: float) -> list[tuple[float, float]]:
    """(height in a, height in b) for every crest of a at least ``floor`` high and the crest of b nearest to it
    (within 10 um along z: a flat crest's position moves by its height error over its slope)."""
    out = []
    for z, h in zip(a.z, a.height, strict=True):
        if h >= floor:
            j = int(np.argmin(np.abs(b.z - z)))
            assert abs(b.z[j] - z) < 10 * UM
            out.append((h, b.height[j]))
    return out


@pytest.mark.parametrize("name", ["hull", "loft", "symmetric", "hard"])
def test_manifold_solid_has_the_envelopes_crests(solids, name: str):
    """Every crest over 0.5 um of either has its partner in the other; where two paths nearly coincide the nose
    polygons (sag <= 0.1 um) leave bumps of that order the envelope has not, hence the floor."""
    cut = solids[name]
    assert cut.solid.status() == mf.Error.NoError and cut.solid.genus() == 0 and len(cut.solid.decompose()) == 1
    assert cut.chord_error <= MESH_TOL and cut.nose_error <= 0.1 * UM
    for phi in np.linspace(0.05, 6.2, 8):
        exact = crest_heights(cut.setup.surface(float(phi), cut.n_revs))
        mesh = solid_crests(cut, float(phi))
        pairs = _pairs(exact, mesh, 0.5 * UM) + [(h, g) for g, h in _pairs(mesh, exact, 0.5 * UM)]
        assert len(pairs) >= 6
        err = max(abs(h - g) for h, g in pairs)
        assert err < MESH_TOL + 0.5 * UM
        assert err < cut.chord_error + cut.nose_error
        if cut.setup.vibration is None:
            assert len(mesh.z) == len(exact.z)
            assert np.max(np.abs(mesh.height - H_S0)) < MESH_TOL + 0.5 * UM
            assert np.allclose(mesh.spacing, S0, atol=1e-4)
