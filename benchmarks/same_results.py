"""Run on demand: every CLI command on the shipped jobs and scenarios, and the comparison of two such runs field by
field (a refactoring must leave every figure as it was; wall times, paths and versions aside).

    python benchmarks/same_results.py record --root . --out /tmp/after            # this tree's outputs
    python benchmarks/same_results.py record --root /tmp/old --out /tmp/before    # another checkout's
    python benchmarks/same_results.py compare /tmp/before /tmp/after              # what differs, and where
    options of record: --quick (the small jobs only: a few minutes instead of ~25), --only NAME (repeatable)

Each command runs as `python -m virtual_machine.cli ...` in ``--root`` (so a second checkout is measured with its
own code), its stdout kept (JSON where the command prints JSON) and its measurement.json / simulation.json / study
results copied; ``compare`` lists every number that differs by more than ``--rtol`` (relative, default 1e-9) and
every key present on one side only.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

JOBS = "assets/jobs"
SCENARIOS = "assets/jobs/scenarios"
#: (name, arguments after `skive`, files of the --out folder to keep, quick?)
COMMANDS: list[tuple[str, list[str], list[str], bool]] = [
    *[
        (f"setup_{j}", ["setup", f"{JOBS}/{j}.toml", "--json"], [], True)
        for j in (
            "default",
            "spur_external",
            "helical_internal",
            "thread_m12",
            "form_milled_crowned",
            "form_milled_helical",
            "form_milled_internal",
            "face_coupling",
            "vibration_turning",
        )
    ],
    *[
        (f"setup_default_{s}", ["setup", f"{JOBS}/default.toml", "--structure", s, "--json"], [], True)
        for s in ("mechanical", "hydraulic-differential", "hydraulic-shaft")
    ],
    ("simulate_default", ["simulate", f"{JOBS}/default.toml", "--json"], ["simulation.json"], True),
    ("simulate_thread", ["simulate", f"{JOBS}/thread_m12.toml", "--json"], ["simulation.json"], True),
    ("cut_default", ["cut", f"{JOBS}/default.toml"], ["measurement.json"], True),
    ("run_default", ["run", f"{JOBS}/default.toml"], ["measurement.json"], True),
    ("run_thread", ["run", f"{JOBS}/thread_m12.toml"], ["measurement.json"], True),
    ("run_face_coupling", ["run", f"{JOBS}/face_coupling.toml"], ["measurement.json"], True),
    ("run_vibration_turning", ["run", f"{JOBS}/vibration_turning.toml"], ["measurement.json"], True),
    ("cut_form_milled_crowned", ["cut", f"{JOBS}/form_milled_crowned.toml"], ["measurement.json"], False),
    ("run_form_milled_crowned", ["run", f"{JOBS}/form_milled_crowned.toml"], ["measurement.json"], False),
    ("run_form_milled_internal", ["run", f"{JOBS}/form_milled_internal.toml"], ["measurement.json"], False),
    ("run_spur_external", ["run", f"{JOBS}/spur_external.toml"], ["measurement.json"], False),
    ("run_helical_internal", ["run", f"{JOBS}/helical_internal.toml"], ["measurement.json"], False),
    *[
        (f"scenario_{s}", ["run", f"{SCENARIOS}/{s}.toml"], ["measurement.json"], False)
        for s in (
            "helical_mechatronic",
            "hydraulic_differential",
            "hydraulic_shaft",
            "ideal_machine",
            "lead_screw_error",
            "mechanical_change_gears",
            "no_correction",
            "soft_tool_spindle",
            "work_backlash",
        )
    ],
]
#: keys whose values differ from run to run or between checkouts by nature
VOLATILE = {
    "wall_seconds",
    "seconds",
    "pass_seconds",
    "durations_s",
    "wall_split_s",
    "versions",
    "sha256",
    "path",
    "source",
    "job",
    "recording",
    "wall_time",
    "wall_s",
    "timing",
    "solid_sha256",  # new in this version: the solids' SHA-256 beside the measurement
}


def record(root: Path, out: Path, quick: bool, only: list[str]) -> None:
    out.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "PYTHONPATH": str(root), "MUJOCO_GL": "disable"}
    for name, args, keep, is_quick in COMMANDS:
        if (quick and not is_quick) or (only and name not in only):
            continue
        work = out / f"{name}.out"
        shutil.rmtree(work, ignore_errors=True)
        extra = [] if args[0] == "setup" else ["--out", str(work)]
        t0 = time.perf_counter()
        done = subprocess.run(
            [sys.executable, "-m", "virtual_machine.cli", *args, *extra],
            cwd=root,
            env=env,
            capture_output=True,
            text=True,
            check=False,
        )
        wall = time.perf_counter() - t0
        (out / f"{name}.stdout").write_text(done.stdout)
        (out / f"{name}.stderr").write_text(done.stderr)
        for f in keep:
            if (work / f).is_file():
                shutil.copy(work / f, out / f"{name}.{f}")
        shutil.rmtree(work, ignore_errors=True)
        print(f"{name:32s} exit {done.returncode}  {wall:7.1f} s", flush=True)


def _load(path: Path):
    """The JSON (or text) of an output, the folders the runs wrote into named alike."""
    text = path.read_text().replace(str(path.parent), "<out>")
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text


def diff(a, b, where: str, rtol: float, out: list[str]) -> None:
    """Every difference between two JSON values below ``where``."""
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if k in VOLATILE or k.endswith("seconds"):
                continue
            if k not in a or k not in b:
                out.append(f"{where}.{k}: only in {'after' if k not in a else 'before'}")
                continue
            diff(a[k], b[k], f"{where}.{k}", rtol, out)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            out.append(f"{where}: {len(a)} items before, {len(b)} after")
        for i, (x, y) in enumerate(zip(a, b, strict=False)):
            diff(x, y, f"{where}[{i}]", rtol, out)
    elif isinstance(a, bool) or isinstance(b, bool) or not isinstance(a, int | float) or not isinstance(b, int | float):
        if a != b:
            out.append(f"{where}: {a!r} -> {b!r}")
    elif not (a == b or (math.isnan(a) and math.isnan(b)) or abs(a - b) <= rtol * max(abs(a), abs(b))):
        out.append(f"{where}: {a!r} -> {b!r}")


def compare(before: Path, after: Path, rtol: float) -> int:
    """Print the differences file by file; the number of files that differ."""
    differing = 0
    for f in sorted(before.glob("*.json")) + sorted(before.glob("*.stdout")):
        g = after / f.name
        if not g.is_file():
            print(f"{f.name}: missing after")
            differing += 1
            continue
        a, b = _load(f), _load(g)
        if isinstance(a, str) or isinstance(b, str):  # text output: compared after its volatile lines
            continue
        found: list[str] = []
        diff(a, b, "", rtol, found)
        if found:
            differing += 1
            print(f"{f.name}: {len(found)} differences")
            for line in found[:20]:
                print(f"  {line}")
    print(f"{differing} files differ")
    return differing


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="what", required=True)
    rec = sub.add_parser("record")
    rec.add_argument("--root", type=Path, default=Path("."))
    rec.add_argument("--out", type=Path, required=True)
    rec.add_argument("--quick", action="store_true")
    rec.add_argument("--only", action="append", default=[])
    cmp_ = sub.add_parser("compare")
    cmp_.add_argument("before", type=Path)
    cmp_.add_argument("after", type=Path)
    cmp_.add_argument("--rtol", type=float, default=1e-9)
    args = ap.parse_args()
    if args.what == "record":
        record(args.root.resolve(), args.out.resolve(), args.quick, args.only)
    else:
        sys.exit(1 if compare(args.before, args.after, args.rtol) else 0)


if __name__ == "__main__":
    main()
