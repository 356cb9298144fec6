"""Form milling by the copying method (seed 003): the profiled mill, its path, its exact swept surface, the removal
and the force."""
