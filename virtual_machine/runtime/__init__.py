"""The machines' run: the CNC program, the physics, the fixed tick loops of the skiving machine and the thread lathe."""
