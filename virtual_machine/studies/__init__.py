"""Studies: many runs of one job with machine parts varied (a study file), on Dask, and the error budget that says
which part limits the gear's ISO 1328-1 class."""
