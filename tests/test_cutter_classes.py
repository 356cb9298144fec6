"""The cutter's tolerance classes (cutting/skiving/cutter_classes.py): DIN 3968's figures by class and module, as the
cited catalogue prints them (known answers read off its table)."""

from __future__ import annotations

import pytest

from cutting.skiving.cutter_classes import cutter_tolerances


@pytest.mark.parametrize(
    ("cls", "module", "expected"),
    [
        ("AA", 2.0, {"radial_runout": 12, "axial_runout": 3, "pitch": 12, "profile": 6}),  # > 1.6-2.5 (spur_external)
        ("A", 1.0, {"radial_runout": 12, "axial_runout": 3, "pitch": 12, "profile": 10}),  # > 0.63-1 (upper edge)
        ("B", 6.3, {"radial_runout": 63, "axial_runout": 6, "pitch": 63, "profile": 32}),  # > 4-6.3
        ("A", 6.31, {"radial_runout": 40, "axial_runout": 8, "pitch": 40, "profile": 20}),  # > 6.3-10
    ],
)
def test_the_tolerances_are_the_tables(cls: str, module: float, expected: dict) -> None:
    got = cutter_tolerances(cls, module)
    assert got == pytest.approx({k: v * 1e-3 for k, v in expected.items()})


def test_a_class_or_module_outside_the_table_is_refused() -> None:
    with pytest.raises(ValueError, match="use one of AA, A, B"):
        cutter_tolerances("C1", 2.0)
    with pytest.raises(ValueError, match=r"covers 0\.63-40 mm"):
        cutter_tolerances("AA", 0.5)
