"""The study case store serves a case only to the skive that made it: its key holds skive's version (release and
the fingerprint of the code and data) beside the job's content."""

from __future__ import annotations

from pathlib import Path

from checks import JOBS

from virtual_machine.studies.cache import CaseCache, content_key
from virtual_machine.version import skive_version, source_fingerprint

OK = {"status": "ok", "error": "", "wall_s": 1.0, "measurement": {"iso1328": {"class": {"overall": 5}}}}


def test_an_entry_of_another_skive_version_is_not_served(tmp_path: Path) -> None:
    text = (JOBS / "default.toml").read_text()
    old = CaseCache(tmp_path, version="0.1.0+src.000000000000")
    assert old.put(text, OK) and old.get(text) == OK
    now = CaseCache(tmp_path)  # this skive: the same job runs again
    assert now.version == skive_version() != old.version
    assert now.get(text) is None and content_key(text) != content_key(text, old.version)
    assert now.put(text, {**OK, "wall_s": 2.0}) and now.get(text)["wall_s"] == 2.0 and old.get(text) == OK


def test_an_entry_whose_version_was_rewritten_is_not_served(tmp_path: Path) -> None:
    """The key file's name is not the only guard: the entry's own version must be this skive's."""
    text = (JOBS / "default.toml").read_text()
    store = CaseCache(tmp_path)
    assert store.put(text, OK)
    path = store.path(text)
    path.write_text(path.read_text().replace(store.version, "0.0.1+src.ffffffffffff"))
    assert store.get(text) is None


def test_the_version_follows_the_code_and_the_material_data(tmp_path: Path) -> None:
    assert skive_version().endswith(f"+src.{source_fingerprint()}")
    (tmp_path / "cutting").mkdir()
    (tmp_path / "assets").mkdir()
    module, data = tmp_path / "cutting" / "forces.py", tmp_path / "assets" / "materials.toml"
    module.write_text("KC = 1700.0\n")
    data.write_text("mc = 0.25\n")
    prints = [source_fingerprint(tmp_path / "a")]  # no code at all
    for path, text in ((module, "KC = 1800.0\n"), (data, "mc = 0.26\n")):
        source_fingerprint.cache_clear()
        prints.append(source_fingerprint(tmp_path))
        path.write_text(text)
    source_fingerprint.cache_clear()
    prints.append(source_fingerprint(tmp_path))
    assert len(set(prints)) == len(prints) == 4  # each change makes another version
