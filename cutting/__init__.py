"""Cutting: gear and tool geometry (ISO 21771), and every process's removal, exact swept surface and forces; it
knows no machine and measures nothing."""
