"""Form milling by the copying method (seed 003): the profiled mill, its path, its exact swept surface, the removal
and the force."""

#: the forms a pass's path takes through its points (cutting.form_milling.copying_path.FlankPath): a C2 cubic spline
#: of Bezier segments (one per interval), or seed 003's single cubic Bezier over the whole path (eq. 17), fitted
PATH_FORMS = ("spline", "bezier")
