"""Error type shared by every stage: a bad input names its key, its value, why and what would do."""

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


class InputError(ValueError):
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
