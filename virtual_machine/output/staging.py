"""A stage's files are all of one run: written into a fresh folder beside the target, moved into place when complete.

A run killed half-way (a signal, an error, a full disk) leaves the target as the previous run left it, never the
new gear.stl beside the old measurement.json. On success the new files replace the old ones; the files the previous
stage in that folder wrote and this one did not (its manifest, ``.skive-outputs.json``) are removed, so a folder
holds one stage's outputs. Documents name their files where they will be (the staging folder's path is rewritten in
the text files and the product), and measurement.json records the SHA-256 of the solids it measured.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import uuid
from pathlib import Path
from typing import Any

from virtual_machine.output.json_file import write_json

MANIFEST = ".skive-outputs.json"
#: text files whose contents may name the staging folder
TEXT_SUFFIXES = (".json", ".html", ".txt", ".csv", ".md")


def sha256_of(path: Path) -> str:
    h = hashlib.sha256()
    with path.open("rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _replace_strings(node: Any, old: str, new: str) -> Any:
    if isinstance(node, str):
        return node.replace(old, new)
    if isinstance(node, dict):
        return {k: _replace_strings(v, old, new) for k, v in node.items()}
    if isinstance(node, list):
        return [_replace_strings(v, old, new) for v in node]
    return node


class StagedOutputs:
    """The staging folder of one stage's outputs for ``out`` (and the recording ``rrd``, wherever it goes).

    Use as a context manager: ``folder`` and ``rrd_staged`` are where the stage writes; :meth:`publish` moves
    everything into place; leaving the block removes what is left of the staging folder (a failed or killed stage).
    """

    def __init__(self, out: Path, rrd: Path | None = None) -> None:
        self.out = Path(out)
        self.rrd = None if rrd is None else Path(rrd)
        self.folder = self.out.parent / f".{self.out.name}.partial-{uuid.uuid4().hex[:12]}"
        self.rrd_staged = None if self.rrd is None else self.folder / ".recording" / self.rrd.name

    def __enter__(self) -> StagedOutputs:
        self.folder.mkdir(parents=True)
        return self

    def __exit__(self, *exc) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)

    def _files(self) -> list[Path]:
        return sorted(p for p in self.folder.rglob("*") if p.is_file() and ".recording" not in p.parts)

    def publish(self, data: Any, text: str) -> tuple[Any, str, list[Path]]:
        """Move the staged files into ``out`` (and the recording to ``rrd``); returns ``data`` and ``text`` with
        the staging folder's path replaced by the target's, and the files as published."""
        files = self._files()
        measurement = self.folder / "measurement.json"
        solids = {p.name: sha256_of(p) for p in files if p.suffix == ".stl" and p.parent == self.folder}
        if measurement.is_file() and isinstance(data, dict) and solids:
            data = {**data, "solid_sha256": solids}  # the solids this measurement belongs to
            write_json(measurement, {**json.loads(measurement.read_text()), "solid_sha256": solids})
        for p in files:
            if p.suffix in TEXT_SUFFIXES:
                content = p.read_text(errors="surrogateescape")
                changed = content
                for old, new in self._renames():
                    changed = changed.replace(old, new)
                if changed != content:
                    p.write_text(changed, errors="surrogateescape")
        self.out.mkdir(parents=True, exist_ok=True)
        relative = [p.relative_to(self.folder) for p in files]
        for rel in _previous_outputs(self.out):
            if rel not in relative and (self.out / rel).is_file():
                (self.out / rel).unlink()
        published = []
        for rel in relative:
            target = self.out / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            os.replace(self.folder / rel, target)
            published.append(target)
        (self.out / MANIFEST).write_text(json.dumps([str(r) for r in relative]))
        if self.rrd_staged is not None and self.rrd_staged.is_file():
            self.rrd.parent.mkdir(parents=True, exist_ok=True)
            os.replace(self.rrd_staged, self.rrd)
            published.append(self.rrd)
        for old, new in self._renames():
            data, text = _replace_strings(data, old, new), text.replace(old, new)
        return data, text, published

    def _renames(self) -> list[tuple[str, str]]:
        """The staged paths' strings and their final ones: the recording's first (it lies inside the folder)."""
        rrd = [] if self.rrd is None else [(str(self.rrd_staged), str(self.rrd))]
        return [*rrd, (str(self.folder), str(self.out))]


def _previous_outputs(out: Path) -> list[Path]:
    """The files the last stage published into ``out`` (its manifest), relative to it."""
    try:
        names = json.loads((out / MANIFEST).read_text())
    except (FileNotFoundError, json.JSONDecodeError):
        return []
    return [Path(n) for n in names if isinstance(n, str) and not Path(n).is_absolute() and ".." not in Path(n).parts]
