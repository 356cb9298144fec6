"""Suite-wide pytest configuration.

The suite runs on two processes with whole files per process (pyproject: ``-n 2 --dist loadfile``); a file is
handed to the next free process in collection order, so a long file collected last would run alone at the end.
The files that take minutes are collected first (their order here, measured on the 2-core CI machine), the rest
after them in their usual order: the two processes then finish within a short file of each other.
"""

from __future__ import annotations

import os

import pytest
from shared_runs import SharedRuns

#: test files by wall time, longest first (the scenario fixture and the studies run whole machine jobs)
LONG_FIRST = (
    "test_scenarios.py",
    "test_study.py",
    "test_modification.py",
    "test_form_milling_cli.py",
    "test_run.py",
    "test_cosim.py",
    "test_cut_measurement.py",
    "test_sampled_motion.py",
    "test_copying.py",
    "test_vibration_lathe.py",
)


def pytest_collection_modifyitems(session, config, items) -> None:
    rank = {name: i for i, name in enumerate(LONG_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))  # stable: the rest keep their order


@pytest.fixture(scope="session")
def shared_runs(tmp_path_factory) -> SharedRuns:
    """Whole-machine runs shared by the test files of this session (tests/shared_runs.py): under xdist in the
    session's directory above each process's own, so every process of the session finds them."""
    base = tmp_path_factory.getbasetemp()
    return SharedRuns((base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base) / "shared_runs")
