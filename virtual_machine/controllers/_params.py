"""Parameter checks shared by the controller blocks.

Each check returns the value converted to the plain Python type the block's ``update`` uses (``int`` or
``float``) or raises ``ValueError`` naming the parameter, its value and the valid range.
"""

from __future__ import annotations

import math
from numbers import Integral, Real


def integer_at_least(name: str, value: object, minimum: int) -> int:
    """Return ``value`` as ``int`` if it is an integer (not a bool) >= ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, Integral) or value < minimum:
        raise ValueError(f"{name} = {value!r} is invalid: must be an integer >= {minimum}")
    return int(value)


def integer_in(name: str, value: object, allowed: tuple[int, ...]) -> int:
    """Return ``value`` as ``int`` if it is one of the integers ``allowed``."""
    if isinstance(value, bool) or not isinstance(value, Integral) or value not in allowed:
        raise ValueError(f"{name} = {value!r} is invalid: must be one of {allowed}")
    return int(value)


def _real(name: str, value: object, rule: str) -> float:
    if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value):
        raise ValueError(f"{name} = {value!r} is invalid: must be a finite number {rule}")
    return float(value)


def positive(name: str, value: object) -> float:
    """Return ``value`` as ``float`` if it is finite and > 0."""
    x = _real(name, value, "> 0")
    if x <= 0.0:
        raise ValueError(f"{name} = {value!r} is out of range: must be finite and > 0")
    return x


def non_negative(name: str, value: object) -> float:
    """Return ``value`` as ``float`` if it is finite and >= 0."""
    x = _real(name, value, ">= 0")
    if x < 0.0:
        raise ValueError(f"{name} = {value!r} is out of range: must be finite and >= 0")
    return x


def nonzero(name: str, value: object) -> float:
    """Return ``value`` as ``float`` if it is finite and != 0 (a gain; its sign is allowed)."""
    x = _real(name, value, "!= 0")
    if x == 0.0:
        raise ValueError(f"{name} = {value!r} is out of range: must be finite and != 0")
    return x


def finite(name: str, value: object) -> float:
    """Return ``value`` as ``float`` if it is finite (any sign)."""
    return _real(name, value, "(any sign)")
