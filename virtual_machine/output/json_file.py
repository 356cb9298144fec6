"""The JSON files a stage writes (measurement.json, simulation.json) and the CLI's --json: one cleaner, one format.

JSON has no NaN or infinity: they become null (an infinite lead: a spur gear); numpy scalars become numbers and
private keys (``_...``) are dropped (:func:`metrology.charts.finite`, which the measurement documents use).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from metrology.charts import finite


def json_text(doc: Any) -> str:
    """``doc`` as the files and the CLI print it: cleaned, indented by two."""
    return json.dumps(finite(doc), indent=2, allow_nan=False)


def write_json(path: Path, doc: Any) -> Path:
    """Write ``doc`` (cleaned) to ``path``; returns the path."""
    path.write_text(json_text(doc))
    return path
