"""The gear measuring machine: a workpiece (a mesh or a cut's exact swept surface) probed as a measuring machine
probes it, the ISO 1328-1 deviations and class, the charts."""
