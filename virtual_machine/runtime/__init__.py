"""The machines' run: the one machine loop every machine runs (:mod:`.loop`, :mod:`.integrator`), the skiving
machine on it (its CNC program, physics and stepper) and the lathe of seed 001."""
