"""Vibration turning (seed 004): the feed vibration, the crests it leaves, the turned surface."""
