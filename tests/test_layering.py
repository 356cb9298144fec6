"""The one-way arrows between the packages: ``machine_models`` is built
from numeric layouts and imports neither ``cutting`` nor ``virtual_machine``; ``cutting`` and ``metrology`` import
neither ``virtual_machine`` nor ``machine_models``. Every import of every module counts, also those inside functions."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

FORBIDDEN = {
    "machine_models": ("cutting", "virtual_machine"),
    "cutting": ("virtual_machine", "machine_models"),
    "metrology": ("virtual_machine", "machine_models"),
}


def _imports(path: Path) -> list[tuple[int, str]]:
    """(line, absolute module name) of every import in ``path`` (relative imports resolved against its package)."""
    package = path.relative_to(ROOT).with_suffix("").parts[:-1]
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package[: len(package) - node.level + 1] if node.level else ()
            module = ".".join((*base, *([node.module] if node.module else [])))
            out.append((node.lineno, module))
    return out


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_imports_point_one_way(package: str) -> None:
    modules = sorted((ROOT / package).rglob("*.py"))
    assert modules, package
    wrong = [
        f"{path.relative_to(ROOT)}:{line} imports {name}"
        for path in modules
        for line, name in _imports(path)
        if name.split(".")[0] in FORBIDDEN[package]
    ]
    assert not wrong, "\n".join(wrong)


def test_runtime_imports_no_process_and_no_process_another() -> None:
    """The machine loop and the machines' runs (``virtual_machine/runtime``) serve every process and import none; a
    process package imports only its own modules, never another process's (what they share lives outside
    ``processes/``: ``runtime``, ``reach``, ``setting``, ``output`` or ``processes``' own shared modules)."""
    wrong = [
        f"{path.relative_to(ROOT)}:{line} imports {name}"
        for path in sorted((ROOT / "virtual_machine" / "runtime").rglob("*.py"))
        for line, name in _imports(path)
        if name.startswith("virtual_machine.processes")
    ]
    processes = ROOT / "virtual_machine" / "processes"
    for package in sorted(p for p in processes.iterdir() if (p / "__init__.py").is_file()):
        own = f"virtual_machine.processes.{package.name}"
        wrong += [
            f"{path.relative_to(ROOT)}:{line} imports {name}"
            for path in sorted(package.rglob("*.py"))
            for line, name in _imports(path)
            if name.startswith("virtual_machine.processes.")
            and (ROOT / Path(*name.split(".")[:3]) / "__init__.py").is_file()
            and not (name == own or name.startswith(own + "."))
        ]
    assert not wrong, "\n".join(wrong)


def test_only_the_runtime_steps_mujoco() -> None:
    """Every machine runs on the machine loop (virtual_machine/runtime/loop.py); nothing else calls mj_step."""
    steppers = [
        f"{path.relative_to(ROOT)}:{n}"
        for package in ("machine_models", "virtual_machine", "cutting", "metrology")
        for path in sorted((ROOT / package).rglob("*.py"))
        for n, line in enumerate(path.read_text().splitlines(), 1)
        if "mj_step" in line and path.parent != ROOT / "virtual_machine" / "runtime"
    ]
    assert not steppers, "\n".join(steppers)
