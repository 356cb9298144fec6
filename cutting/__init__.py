"""Cutting: gear and tool geometry (ISO 21771), and every process's removal, exact swept surface and forces; it
knows no machine and measures nothing."""

from cutting.kernel_cache import keep_in_step as _keep_in_step

_keep_in_step()  # the kernels' caches compiled from these sources, or none (cutting/kernel_cache.py)
