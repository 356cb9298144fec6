"""docs/layout.md lists every module of the four packages (the manual's map of the code stays whole)."""

from __future__ import annotations

from checks import ROOT

PACKAGES = ("cutting", "metrology", "machine_models", "virtual_machine")


def test_every_module_is_in_the_layout() -> None:
    text = (ROOT / "docs" / "layout.md").read_text()
    modules = sorted(p.relative_to(ROOT).as_posix() for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py"))
    assert len(modules) > 100
    missing = [m for m in modules if f"`{m}`" not in text]
    assert not missing, "add these modules to docs/layout.md: " + ", ".join(missing)


def test_the_layout_names_no_module_that_is_gone() -> None:
    text = (ROOT / "docs" / "layout.md").read_text()
    named = {part.strip("`") for part in text.split() if part.startswith("`") and part.rstrip("`|").endswith(".py")}
    gone = sorted(n for n in named if n.split("/")[0] in PACKAGES and not (ROOT / n).is_file())
    assert not gone, "docs/layout.md names modules that do not exist: " + ", ".join(gone)
