"""Suite-wide pytest configuration.

The suite runs on two processes with whole files per process (pyproject: ``-n 2 --dist loadfile``); a file is
handed to the next free process in collection order, so a long file collected last would run alone at the end.
The files that take minutes are collected first (their order here, measured on the 2-core machine), the rest
after them in their usual order: the two processes then finish within a short file of each other. (pytest-xdist
would otherwise hand out the files with the most tests first, whatever their time: that is switched off here.)

The whole-machine runs several files need (tests/shared_runs.py) are made once per session and shared by the
processes: test_scenarios.py makes those test_study.py's studies take as cases, first thing, while test_study.py
starts with its own small studies on the other process.
"""

from __future__ import annotations

import os

import pytest
from shared_runs import SharedRuns

#: test files by wall time, longest first (measured: the scenario runs and the studies run whole machine jobs); the
#: last few are short but would come last in collection order, alone at the end
LONG_FIRST = (
    "test_scenarios.py",
    "test_study.py",
    "test_machine_effect.py",
    "test_dexel.py",
    "test_form_milling_cli.py",
    "test_modification.py",
    "test_rake_face.py",
    "test_chatter_in_the_run.py",
    "test_cut_measurement.py",
    "test_machine_geometry.py",
    "test_cutter_errors.py",
    "test_one_run_outputs.py",
    "test_measure.py",
    "test_removal.py",
    "test_cosim.py",
    "test_run.py",
    "test_measure_cli.py",
    "test_copying.py",
    "test_sampled_motion.py",
    "test_machine_sizes.py",
    "test_vibration_lathe.py",
    "test_simulate.py",
    "test_vibration_turning.py",
    "test_cut_cli.py",
)


def pytest_configure(config) -> None:
    if hasattr(config.option, "loadscopereorder"):  # pytest-xdist >= 3.6: keep the collection order below
        config.option.loadscopereorder = False


def pytest_collection_modifyitems(session, config, items) -> None:
    rank = {name: i for i, name in enumerate(LONG_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))  # stable: the rest keep their order


@pytest.fixture(scope="session")
def shared_runs(tmp_path_factory) -> SharedRuns:
    """Whole-machine runs shared by the test files of this session (tests/shared_runs.py): under xdist in the
    session's directory above each process's own, so every process of the session finds them."""
    base = tmp_path_factory.getbasetemp()
    return SharedRuns((base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base) / "shared_runs")
