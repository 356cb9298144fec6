"""The small job the tests cut: z2 = 18, mn = 1, one full-depth pass of a 17-tooth cutter (seconds, not minutes)."""

from __future__ import annotations


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
