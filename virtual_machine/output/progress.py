"""Progress that suits where it goes: a bar on a terminal, plain lines in a log.

On a terminal a task shows a tqdm bar. When the output is not a terminal (CI, a pipe, a file) a bar's carriage
returns make an unreadable log, so a task prints one line per ``step`` of its total (10 %) and one at its end,
each readable on its own: ``pass 2/4: 30 % (1701/5664 passages, 42 s)``.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from typing import TextIO


def is_interactive(stream: TextIO | None = None) -> bool:
    """A terminal that shows bars: a tty, not under CI, not a dumb terminal."""
    stream = stream or sys.stderr
    if os.environ.get("CI", "").lower() not in ("", "0", "false", "no"):
        return False
    if os.environ.get("TERM") == "dumb":
        return False
    return bool(getattr(stream, "isatty", lambda: False)())


def stage(name: str, stream: TextIO | None = None) -> None:
    """One line announcing a stage (on a terminal too)."""
    stream = stream or sys.stderr
    print(f"{name} ...", file=stream, flush=True)


class Progress:
    """One task's progress: a tqdm bar on a terminal, a line per ``step`` of the total otherwise.

    ``update_to(value, **info)`` sets the absolute position (info: shown as "key value" after the counts);
    ``set_total`` lets an estimated total grow; ``close`` prints the final line once.
    """

    def __init__(
        self,
        desc: str,
        total: float,
        unit: str = "",
        *,
        stream: TextIO | None = None,
        interactive: bool | None = None,
        step: float = 0.1,
        value_format: str = "{:g}",
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.desc, self.total, self.unit = desc, float(total), unit
        self.stream = stream or sys.stderr
        self.interactive = is_interactive(self.stream) if interactive is None else interactive
        self.step, self.fmt, self.clock = step, value_format, clock
        self.value, self.info = 0.0, {}
        self._start = clock()
        self._printed = -1  # the last step printed (non-interactive)
        self._last_value: float | None = None
        self._closed = False
        self._bar = None
        if self.interactive:
            from tqdm import tqdm

            fmt = "{l_bar}{bar}| {n:.4g}/{total:.4g} " + unit + " [{elapsed}<{remaining}{postfix}]"
            self._bar = tqdm(total=self.total, desc=desc, bar_format=fmt, mininterval=0.5, file=self.stream)

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def set_total(self, total: float) -> None:
        self.total = max(self.total, float(total))
        if self._bar is not None:
            self._bar.total = self.total

    def update_to(self, value: float, **info) -> None:
        self.value = float(value)
        self.info.update(info)
        if self._bar is not None:
            if info:
                self._bar.set_postfix(info, refresh=False)
            self._bar.update(self.value - self._bar.n)
            return
        done = int(self.value / self.total / self.step + 1e-9) if self.total > 0 else 0
        if done > self._printed and done * self.step < 1.0 - 1e-9 and self.value != self._last_value:
            self._printed = done
            self._line()

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        if self._bar is not None:
            self._bar.close()
        else:
            self._line()

    def _line(self) -> None:
        self._last_value = self.value
        pct = 100.0 * min(self.value / self.total, 1.0) if self.total > 0 else 100.0
        counts = f"{self.fmt.format(self.value)}/{self.fmt.format(self.total)}"
        if self.unit:
            counts += f" {self.unit}"
        extra = "".join(f", {v} {k.replace('_', ' ')}" for k, v in self.info.items())
        elapsed = self.clock() - self._start
        print(f"{self.desc}: {pct:.0f} % ({counts}{extra}, {elapsed:.0f} s)", file=self.stream, flush=True)


class _Null:
    """A stream that takes everything and shows nothing."""

    def write(self, _text: str) -> int:
        return 0

    def flush(self) -> None:
        pass


class Reporter:
    """Where a process says how it goes: stages (one line each) and tasks with a total (a :class:`Progress`).

    A task lasts until the next stage or :meth:`close`. The CLI's reporter writes to stderr (bars on a terminal,
    lines in a log); ``Reporter(quiet=True)`` says nothing (a notebook that wants only the result)."""

    def __init__(self, stream: TextIO | None = None, *, quiet: bool = False) -> None:
        self.stream = _Null() if quiet else stream
        self._tasks: list[Progress] = []

    def stage(self, name: str) -> None:
        self.close()
        stage(name, self.stream)

    def task(self, desc: str, total: float, unit: str = "", **options) -> Progress:
        """A task's progress; ``options`` as :class:`Progress` takes them (step, value_format)."""
        bar = Progress(desc, total, unit, stream=self.stream, **options)
        self._tasks.append(bar)
        return bar

    def close(self) -> None:
        for bar in self._tasks:
            bar.close()
        self._tasks.clear()

    def __enter__(self) -> Reporter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()  # a stage's bars end with it, also when it fails
