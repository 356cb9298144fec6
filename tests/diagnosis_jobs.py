"""What the diagnosis tests share: a gear cut on a job's machine with errors injected, measured as skive measures
a cut (the exact swept surface), written as measurement.json, and the diagnosis of it against the job."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

from virtual_machine.job import parse_job
from virtual_machine.processes.skiving.machine_added import exact_measurement


def measured_with(job_path: Path, errors: dict[str, float], out: Path) -> Path:
    """The job's gear cut with ``errors`` ([machine.model.geometry] keys in the job's units), measured, as
    measurement.json in ``out``."""
    lines = "\n".join(f"{k} = {v!r}" for k, v in errors.items())
    text = job_path.read_text() + f"\n[machine.model.geometry]\n{lines}\n"
    out.mkdir(parents=True, exist_ok=True)
    path = out / "measurement.json"
    path.write_text(json.dumps(exact_measurement(parse_job(tomllib.loads(text), str(job_path)))))
    return path


def check_round_trip(outcome, errors: dict[str, float], tolerance: float = 0.20, phase_deg: float = 10.0) -> None:
    """The injected sources ranked first (each amplitude key once), their values within ``tolerance`` and their
    phases within ``phase_deg``."""
    injected = {k: v for k, v in errors.items() if not k.endswith("_phase")}
    causes = outcome.diagnosis.causes
    top = causes[: len(injected)]
    assert {c.key.rsplit(".", 1)[-1] for c in top} == set(injected), [(c.key, c.value, c.confidence) for c in causes]
    for c in top:
        name = c.key.rsplit(".", 1)[-1]
        assert abs(c.value - injected[name]) <= tolerance * abs(injected[name]), (name, c.value, injected[name])
        phase = name.replace("_error", "_phase").replace("_eccentricity", "_phase")
        if c.phase_deg is not None and phase in errors:
            off = (c.phase_deg - errors[phase] + 180.0) % 360.0 - 180.0
            assert abs(off) <= phase_deg, (name, c.phase_deg, errors[phase])
