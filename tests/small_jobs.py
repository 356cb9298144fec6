"""The small job the tests cut: z2 = 18, mn = 1, one full-depth pass of a 17-tooth cutter (seconds, not minutes)."""

from __future__ import annotations


def small_job(edge: str | None = "involute", sweep_error: float = 0.004, face_width: float = 2.0) -> str:
    """Job text; ``edge`` None leaves the job's default (conjugate); b >= 4 mm makes it ISO 1328-1 gradable."""
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
axial_feed = 0.2
passes = [2.25]
sweep_error = {sweep_error}
"""
