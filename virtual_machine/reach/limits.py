"""One wording for a job beyond one of its machine's limits (a ``[machine.model]`` key): what the machine cannot do,
what would do instead, and the key a real machine's own figure goes in."""

from __future__ import annotations

from cutting.errors import Problem


def beyond_limit(machine: str, key: str, limit: float, need: float, unit: str, what: str, less: str) -> Problem:
    """The problem of a job that needs ``need`` [``unit``] of the ``machine``'s limit ``key`` (now ``limit``):
    ``what`` it cannot do, ``less`` the job's change that would do."""
    return Problem(
        f"machine.model.{key}",
        limit,
        f"the {machine} cannot do it: {what}",
        f"use {less}, or machine.model.{key} >= {need:.3g} ({unit}) if the real {machine} has it",
    )
