"""The shape every machine's reach check has: a :class:`Limit` per figure of the machine the job needs, each held
against the machine's own (a ``[machine.model]`` parameter), and one wording for a job beyond it; :func:`refuse`
raises them together as a :class:`cutting.errors.MachineLimitError` before anything runs."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from cutting.errors import MachineLimitError, Problem


@dataclass(frozen=True)
class Limit:
    """One limit of the machine: its ``[machine.model]`` parameter ``key`` (now ``limit``), what the job ``need``s of
    it (both in ``unit``), ``what`` the machine cannot do when the need is beyond it, and ``less``: the job's change
    that would do."""

    key: str
    need: float
    limit: float
    unit: str
    what: str
    less: str

    @property
    def holds(self) -> bool:
        return self.need <= self.limit

    def problem(self, machine: str) -> Problem:
        """The problem of a job beyond this limit of the ``machine``."""
        return beyond_limit(machine, self.key, self.limit, self.need, self.unit, self.what, self.less)


def beyond_limit(machine: str, key: str, limit: float, need: float, unit: str, what: str, less: str) -> Problem:
    """The problem of a job that needs ``need`` [``unit``] of the ``machine``'s limit ``key`` (now ``limit``):
    ``what`` it cannot do, ``less`` the job's change that would do."""
    return Problem(
        f"machine.model.{key}",
        limit,
        f"the {machine} cannot do it: {what}",
        f"use {less}, or machine.model.{key} >= {need:.3g} ({unit}) if the real {machine} has it",
    )


def refuse(machine: str, limits: Iterable[Limit], problems: Iterable[Problem] = (), source: str = "") -> None:
    """Raise MachineLimitError with ``problems`` and one for every limit of ``limits`` the job is beyond (nothing
    when all hold)."""
    found = [*problems, *(lim.problem(machine) for lim in limits if not lim.holds)]
    if found:
        raise MachineLimitError(found, source)
