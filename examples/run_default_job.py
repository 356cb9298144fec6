"""Run a job on the simulated machine from Python and read what it made.

    python examples/run_default_job.py                       # the default job, into ./out
    python examples/run_default_job.py JOB.toml --out DIR    # any job file

The same as `skive setup` then `skive run`, through skive's Python API (virtual_machine's public names).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from virtual_machine import load_job, run, setup
from virtual_machine.job import default_job_path


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("job", nargs="?", type=Path, default=default_job_path(), help="job file (default: the default job)")
    ap.add_argument("--out", type=Path, default=Path("out"), help="where the run writes its files")
    a = ap.parse_args(argv)

    job = load_job(a.job)  # parsed and checked once: a bad job raises InputError saying what to fix
    sheet = setup(job)  # the machine setting sheet (sheet.data: the JSON of `skive setup --json`)
    print(sheet.text.splitlines()[0])

    result = run(job, out=a.out)  # machine, cutting forces, cut, measurement, report
    iso = result.measurement["iso1328"]
    if iso["class"] is None:  # e.g. a face below the standard's 4 mm: the deviations still stand
        print(f"no ISO 1328-1 class: {iso['error']}")
    else:
        print(f"ISO 1328-1 class {iso['class']['overall']}")
    for name in ("F_alpha", "F_beta", "F_p"):  # measured deviation [um]; with a class, its tolerance and class
        line = f"  {name:8s} {iso['measured'][name]:6.2f} um"
        if iso["class"] is not None:
            line += f" (class {iso['tolerances_class']}: {iso['tolerances'][name]:.1f} um), class {iso['class'][name]}"
        print(line)
    print(f"report: {result.report_path}")
    print(f"files: {', '.join(str(f) for f in result.files)}")
    return result.measurement


if __name__ == "__main__":
    main()
