"""Job keys: the :class:`Key` declaration, its value checks and coercion, and :func:`parse_section`.

Every key of a job is declared once, in the table of its section, with its type, unit, default and check;
:func:`parse_section` appends *all* problems of a section, each naming the key, the value, why and what would be
valid. Also the keys several kinds of job share in their [process] (passes, material, cutting speed, STL tolerance).
Units: mm, degrees, rpm, Hz.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, make_dataclass
from typing import Any

from cutting.errors import Problem

REQUIRED = object()

#: a key's check: ``None`` when the value is fine, else ``(reason, hint)``
Check = Callable[[Any], tuple[str, str] | None]


@dataclass(frozen=True)
class Key:
    """One job key: expected type, default (REQUIRED if none), unit, meaning and an optional check.

    ``check(value)`` returns ``None`` when fine, else ``(reason, hint)``.
    """

    kind: type | tuple[type, ...]
    default: Any
    unit: str
    doc: str
    check: Check | None = None


def positive(v: float) -> tuple[str, str] | None:
    return None if v > 0 else ("must be > 0", "give a positive number")


def one_of(*options: str) -> Check:
    def check(v: str) -> tuple[str, str] | None:
        return None if v in options else ("not a known value", "use one of " + ", ".join(repr(o) for o in options))

    return check


def at_least(lo: float) -> Check:
    def check(v: float) -> tuple[str, str] | None:
        return None if v >= lo else (f"must be >= {lo:g}", f"give a value of at least {lo:g}")

    return check


def _passes(v: list) -> tuple[str, str] | None:
    if not v:
        return ("needs at least one pass", "e.g. [2.0, 1.5, 0.8, 0.2]; the last is the finishing pass")
    if not all(isinstance(p, int | float) and not isinstance(p, bool) for p in v):
        return ("must be a list of numbers [mm]", "e.g. [2.0, 1.5, 0.8, 0.2]")
    if v[0] <= 0 or any(p < 0 for p in v):
        return (
            "the first radial infeed increment must be > 0 mm and none negative",
            "drop negative increments; a 0 after the first is a spring pass at the same depth, e.g. [2.0, 1.5, 0.0]",
        )
    return None


# [process] keys several kinds share
PASSES = Key(
    list,
    REQUIRED,
    "mm",
    "radial infeed increments from first touch; the last is the finishing pass (0: a spring pass at the same depth)",
    _passes,
)
MATERIAL = Key(str, "16MnCr5", "", "workpiece material: its cutting-force coefficients (assets/materials.toml)")
CUTTING_SPEED = Key(float, REQUIRED, "m/min", "cutting speed at the thread diameter", positive)
STL_TOLERANCE = Key(
    float, 0.010, "mm", "how far simplifying gear.stl may move its surface (0: the solid as cut)", at_least(0.0)
)


def _type_name(kind: type | tuple[type, ...]) -> str:
    names = {
        int: "an integer",
        float: "a number",
        bool: "true or false",
        str: "a string",
        list: "a list",
        dict: "a table",
    }
    if isinstance(kind, tuple):
        return " or ".join(_type_name(k) for k in kind)
    return names.get(kind, str(kind))


def _coerce(raw: Any, key: Key) -> tuple[Any, str | None]:
    """Value of the declared type, or an error message. Integers are accepted where numbers are."""
    if key.kind is float:
        if isinstance(raw, bool) or not isinstance(raw, int | float):
            return None, "expected a number"
        if not math.isfinite(raw):
            return None, "expected a finite number"
        return float(raw), None
    if key.kind is int:
        if isinstance(raw, bool) or not isinstance(raw, int):
            return None, "expected an integer"
        return raw, None
    if isinstance(key.kind, tuple) and float in key.kind and isinstance(raw, int | float) and not isinstance(raw, bool):
        return _coerce(raw, Key(float, key.default, key.unit, key.doc))  # a number where a number or a list will do
    if not isinstance(raw, key.kind):
        return None, f"expected {_type_name(key.kind)}"
    return raw, None


def parse_section(name: str, table: Any, keys: dict[str, Key], problems: list[Problem]) -> dict[str, Any]:
    """Typed values of one section with defaults filled in; problems appended, never raised here."""
    out: dict[str, Any] = {}
    if not isinstance(table, dict):
        problems.append(Problem(name, table, "must be a table", f"write it as [{name}] with key = value lines"))
        return out
    for k in table:
        if k not in keys:
            close = [
                c for c in keys if c.replace("_", "") in k.replace("_", "") or k.replace("_", "") in c.replace("_", "")
            ] or difflib.get_close_matches(k, list(keys), n=1, cutoff=0.8)  # a letter left out, swapped, doubled
            hint = f"did you mean {close[0]!r}? " if close else ""
            problems.append(Problem(f"{name}.{k}", table[k], "unknown key", hint + "valid keys: " + ", ".join(keys)))
    for k, key in keys.items():
        if k not in table:
            if key.default is REQUIRED:
                problems.append(
                    Problem(
                        f"{name}.{k}",
                        None,
                        f"missing required key ({key.doc})",
                        f"add {k} = <{_type_name(key.kind)}{', ' + key.unit if key.unit else ''}>",
                    )
                )
            else:
                out[k] = key.default
            continue
        value, err = _coerce(table[k], key)
        if err:
            hint = f"{key.doc} [{key.unit or '-'}]"
            if key.kind is dict:  # a table written as a plain value
                hint = f"write it as a table, [{name}.{k}] followed by key = value lines: {key.doc}"
            problems.append(Problem(f"{name}.{k}", table[k], err, hint))
            continue
        if key.check is not None:
            bad = key.check(value)
            if bad:
                problems.append(Problem(f"{name}.{k}", table[k], bad[0], bad[1]))
                continue
        out[k] = value
    return out


def parse_sections(
    data: dict[str, Any], sections: dict[str, dict[str, Key]], problems: list[Problem]
) -> dict[str, dict[str, Any]]:
    """:func:`parse_section` of each of ``sections`` in its order (a missing section: an empty table)."""
    return {name: parse_section(name, data.get(name, {}), keys, problems) for name, keys in sections.items()}


def unknown_sections(data: dict[str, Any], allowed: Iterable[str], listed: Iterable[str]) -> list[Problem]:
    """A problem for each section of ``data`` not ``allowed``; the hint lists the ``listed`` ones."""
    allowed, listed = set(allowed), list(listed)
    hint = "valid sections: " + ", ".join(f"[{s}]" for s in listed)
    return [Problem(name, "[section]", "unknown section", hint) for name in data if name not in allowed]


def section_class(name: str, keys: dict[str, Key], doc: str, module: str, extra: dict[str, type] | None = None) -> type:
    """A section's typed values: a frozen dataclass named ``name`` with one field per key of ``keys`` (its declared
    type, or None where the key has no value), and the fields ``extra`` the parser derives; ``module`` is where the
    class is bound to ``name`` (it pickles by that name). The key tables stay the one declaration of every key; the
    parsed job reads ``job.process.tool_speed``, not a string lookup."""
    fields = [(k, _annotation(key.kind) | None, field(default=None, metadata={"key": key})) for k, key in keys.items()]
    fields += [(k, kind | None, field(default=None)) for k, kind in (extra or {}).items()]
    cls = make_dataclass(name, fields, frozen=True, namespace={"__doc__": doc})
    cls.__module__ = module
    return cls


def _annotation(kind: type | tuple[type, ...]) -> Any:
    if isinstance(kind, tuple):
        out = kind[0]
        for k in kind[1:]:
            out = out | k
        return out
    return kind
