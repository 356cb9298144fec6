"""Whether a job is within its machine's reach, one module per machine, each checked before the machine runs: the
workpiece, module or swing it takes, its spindles' top speeds, its slides' travel, its motors' torque under the
cut. Each check holds the job's needs against the machine's ``[machine.model]`` figures (:mod:`.limits`: one shape,
one wording) and raises :class:`cutting.errors.MachineLimitError` naming the limit, both figures and what would do.

- :mod:`.skiving`: the skiving machine's reach per size; :mod:`.skiving_load`: its motors against the estimated cut;
- :mod:`.lathe`: seed 001's lathe (thread and turning jobs);
- :mod:`.form_mill`: the form-milling machine (seed 003);
- :mod:`.face`: the face-contour machine (seed 004), its reach and its motors against the cut.
"""
