"""The small job the tests cut: z2 = 18, mn = 1, one full-depth pass of a 17-tooth cutter (seconds, not minutes)."""

from __future__ import annotations

from pathlib import Path


def small_job(
    edge: str | None = "involute", sweep_error: float = 0.004, face_width: float = 2.0, axial_feed: float = 0.2
) -> str:
    """Job text; ``edge`` None leaves the job's default (conjugate); b >= 4 mm makes it ISO 1328-1 gradable;
    ``axial_feed`` [mm per work turn] 0.4 halves the strokes where a test reads nothing that depends on the feed."""
    edge_line = f'edge = "{edge}"\n' if edge else ""
    return f"""
[gear]
teeth = 18
normal_module = 1.0
face_width = {face_width}

[cutter]
teeth = 17
helix_angle = 20.0
{edge_line}
[process]
tool_speed = 2000.0
axial_feed = {axial_feed}
passes = [2.25]
sweep_error = {sweep_error}
"""


def turning_job(
    vibration: str = "", revolutions: int = 30, sync: str = "master-slave", process: str = "", machine: str = ""
) -> str:
    """The vibration-turning job the tests run (40 mm, S0 0.2 mm, r_eps 0.8 mm, a_p 0.3 mm, 25 m/min): ``vibration``
    a [vibration] section or "", extra ``process`` and ``machine`` lines."""
    return f"""
[turning]
diameter = 40.0
feed = 0.2
nose_radius = 0.8
depth = 0.3
{vibration}
[process]
cutting_speed = 25.0
revolutions = {revolutions}
{process}
[machine]
synchronization = "{sync}"
{machine}
"""


def job_from_text(tmp_path: Path, text: str, name: str = "job.toml"):
    """The job of ``text``, written to ``tmp_path / name`` and loaded as `skive` loads a job file."""
    from virtual_machine.job import load_job

    path = tmp_path / name
    path.write_text(text)
    return load_job(path)
