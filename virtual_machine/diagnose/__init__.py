"""`skive diagnose`: which part of the machine made a measured gear's deviations, fitted from the signatures of a
sensitivity study around the job (docs/diagnose.md).

- :mod:`~virtual_machine.diagnose.measured`: the measured gear (skive's measurement.json, or the documented CSV)
- :mod:`~virtual_machine.diagnose.sources`: the error sources, their probes, the sensitivity study's cases
- :mod:`~virtual_machine.diagnose.fit`: the gears as vectors, the forward selection and the values
- :mod:`~virtual_machine.diagnose.pipeline`: the study in the case store, the checks, the files
"""
