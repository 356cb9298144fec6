"""The errors skive reports to its user, under one base: what went wrong, and what to do about it.

- :class:`InputError`: a job, option or file that is wrong; it names every problem (key, value, why, what would do).
  :class:`MachineLimitError` is one the machine's own figures decide (its reach, its motors' torque).
- :class:`RunError`: a run that started and could not finish (the integration diverged, the machine lost
  synchronism, the gear it cut cannot be measured); the message says which part to change.
- :class:`UnmeasurableError`: the measuring machine cannot take a workpiece (a ball finds no seat, a flank is
  missing).

The command line catches :class:`SkiveError` once (exit status 2); the Python API raises these as they are.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Problem:
    """One thing wrong with an input.

    key:    dotted path of the offending input, e.g. ``"gear.profile_shift"``
    value:  the value found (``None`` when missing)
    reason: why it is wrong, with the numbers that decide it
    hint:   what would be valid
    """

    key: str
    value: object
    reason: str
    hint: str

    def __str__(self) -> str:
        return f"{self.key} = {self.value!r}: {self.reason}; {self.hint}"


class SkiveError(Exception):
    """Every error skive reports to its user; the message says what is wrong and how to fix it."""


class InputError(SkiveError, ValueError):
    """Invalid input. Carries every :class:`Problem` found, not just the first."""

    def __init__(self, problems: list[Problem] | Problem, source: str = ""):
        self.problems = [problems] if isinstance(problems, Problem) else list(problems)
        self.source = source
        head = f"invalid input in {source}" if source else "invalid input"
        lines = [f"{head} ({len(self.problems)} problem{'s' if len(self.problems) != 1 else ''}):"]
        lines += [f"  - {p}" for p in self.problems]
        super().__init__("\n".join(lines))

    @property
    def keys(self) -> list[str]:
        return [p.key for p in self.problems]


class MachineLimitError(InputError):
    """A job beyond its machine: the workpiece or module it takes, its spindles' top speeds, its travel, its motors'
    torque; each problem names the limit, both figures and what would hold it."""


class RunError(SkiveError, RuntimeError):
    """A run that started and could not finish."""


class SimulationDivergedError(RunError):
    """The integration blew up; the message names the stage most likely responsible and how to fix it."""


class LostSynchronismError(RunError):
    """The simulated machine stopped the job (the CNC's alarm), with what happened and what to change."""


class ChatterError(RunError):
    """The machine chattered so hard that the cut tore the gear (its solid is no gear); the message names the pass,
    the vibration and what to change."""


class UnmeasurableGearError(RunError):
    """The machine cut a gear the measuring machine cannot measure (a tooth damaged or missing)."""


class UnmeasurableError(SkiveError, RuntimeError):
    """The workpiece cannot be probed as the nominal gear (a ball finds no seat, a flank is missing): the
    workpiece's fault, not the gear data's, e.g. a tooth the machine damaged."""
