"""The code stays small enough to hold in the head: no function over 80 lines (its body, the docstring aside) outside
the compiled numba kernels, whose loops stay whole for the compiler (ruff's C901 holds their complexity)."""

from __future__ import annotations

import ast

from checks import ROOT

PACKAGES = ("cutting", "metrology", "machine_models", "virtual_machine")
MAX_LINES = 80


def _compiled(node: ast.FunctionDef) -> bool:
    """A numba kernel: decorated with njit or jit (called or not)."""
    for d in node.decorator_list:
        target = d.func if isinstance(d, ast.Call) else d
        name = target.attr if isinstance(target, ast.Attribute) else getattr(target, "id", "")
        if name in ("njit", "jit"):
            return True
    return False


def _body_lines(node: ast.FunctionDef) -> int:
    body = node.body
    has_doc = isinstance(body[0], ast.Expr) and isinstance(getattr(body[0], "value", None), ast.Constant)
    if has_doc and len(body) == 1:
        return 0
    first = body[1] if has_doc else body[0]
    start = min([first.lineno] + [d.lineno for d in getattr(first, "decorator_list", [])])
    return node.end_lineno - start + 1


def test_no_function_outside_the_kernels_is_over_80_lines() -> None:
    long = []
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and not _compiled(node):
                    n = _body_lines(node)
                    if n > MAX_LINES:
                        long.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name}: {n} lines")
    assert not long, "split these functions:\n" + "\n".join(long)


def test_the_kernels_exist_where_the_rule_excuses_them() -> None:
    """The rule's exception is real: the kernels it excuses are compiled numba functions."""
    kernels = set()
    for path in (ROOT / "cutting" / "skiving").glob("*_kernels.py"):
        kernels |= {
            n.name for n in ast.walk(ast.parse(path.read_text())) if isinstance(n, ast.FunctionDef) and _compiled(n)
        }
    assert {"cut_cells", "settle_lines"} <= kernels
