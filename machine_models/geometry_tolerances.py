"""The machine sizes' geometric tolerances: how far a machine of each size may be built off its design in each
geometric error source (issue 43; the sources: cutting/skiving/machine_geometry.py, [machine.model.geometry]).

A study draws machines from them (a Monte-Carlo study's ``machine_tolerances = "medium"``; `skive check
--confidence`): what a population of machines built to these tolerances makes. The tests that measure each are ISO
230-1's (and, for gear hobbing machines, ISO 6545:1992's acceptance tests); ISO 6545's tolerance tables were not at
hand (the stored copies end at its scope), so **every figure below is a guess** of the order a precision gear-cutting
machine's acceptance protocol holds, except the work spindle's radial error, whose order is the runout a milling
machine's spindle nose may show in a Russian acceptance standard's check 1.10 ("radial runout of the taper bore of
the vertical and horizontal spindles", table 8: 6, 5 and 4 um at the nose for the accuracy classes P, V and A,
measured by GOST 22267 section 15; quoted in the normative-terms dictionary, normative_reference_dictionary.
academic.ru/62032): half class A's 4 um as the radial amplitude.
A user with the machine's own acceptance protocol gives its figures as a study's [[vary]] entries instead.

The larger sizes hold coarser figures: medium 1.25 and large 1.6 times the small's (a guess: the ISO 1328 classes'
steps of sqrt(2) per two classes, for machines whose travel and swing are larger).
"""

from __future__ import annotations

#: the signed errors: each machine's value uniform within +-the tolerance
SIGNED = ("shaft_angle_error", "centre_distance_offset", "cutter_offset_error", "carriage_squareness_x",
          "carriage_squareness_y")  # fmt: skip
#: the once-per-turn and periodic errors: each machine's amplitude uniform in [0, tolerance], its phase in [0, 360)
PHASED = {
    "lead_screw_periodic_error": "lead_screw_periodic_phase",
    "work_spindle_radial_error": "work_spindle_radial_phase",
    "work_spindle_tilt_error": "work_spindle_tilt_phase",
    "tool_encoder_eccentricity": "tool_encoder_phase",
    "work_encoder_eccentricity": "work_encoder_phase",
}
#: the small machine's tolerances in the job's units (deg, mm, mm per 100 mm, arcsec): every one a guess but the
#: work spindle's radial error (the module's docstring)
SMALL: dict[str, float] = {
    "shaft_angle_error": 0.003,  # deg: the swivel head set and clamped (5 um over 100 mm)
    "centre_distance_offset": 0.003,  # mm: the radial axis at its reference
    "cutter_offset_error": 0.005,  # mm: the tool spindle's axis off the common perpendicular
    "carriage_squareness_x": 0.003,  # mm per 100 mm of carriage travel
    "carriage_squareness_y": 0.003,  # mm per 100 mm
    "lead_screw_periodic_error": 0.002,  # mm: the carriage's once-per-screw-turn wave
    "work_spindle_radial_error": 0.002,  # mm: half a 4 um runout at the nose (accuracy class A, check 1.10)
    "work_spindle_tilt_error": 0.002,  # mm per 100 mm
    "tool_encoder_eccentricity": 3.0,  # arcsec
    "work_encoder_eccentricity": 3.0,  # arcsec
}
SCALE = {"small": 1.0, "medium": 1.25, "large": 1.6}


def geometry_tolerances(size: str) -> dict[str, float]:
    """The tolerances of a machine of ``size`` ("small", "medium", "large") in the job's units; ValueError for
    another size."""
    if size not in SCALE:
        raise ValueError(f"machine size {size!r}: use one of {', '.join(SCALE)}")
    return {k: v * SCALE[size] for k, v in SMALL.items()}
