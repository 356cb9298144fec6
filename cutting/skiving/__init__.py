"""Gear skiving: the crossed-axes setup, the cutting edge, pose trajectories (ideal and sampled), the removal (the
dexel workpiece; the manifold reference), the exact swept surface, the holder check."""
