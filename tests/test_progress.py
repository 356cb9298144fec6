"""Progress that suits a log: lines per 10 % when not on a terminal, a bar on one."""

import io

from virtual_machine.output.progress import Progress, is_interactive, stage


class Clock:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


def test_a_log_gets_one_line_per_tenth_and_one_at_the_end():
    out, clock = io.StringIO(), Clock()
    with Progress("pass 2/4", 100, "passages", stream=out, interactive=False, clock=clock) as p:
        for k in range(1000):
            clock.t = k / 10
            p.update_to(k / 10, engagements=k)
    lines = out.getvalue().splitlines()
    assert "\r" not in out.getvalue()
    assert len(lines) == 11  # 0 % .. 90 % and the end
    assert lines[3].startswith("pass 2/4: 30 % (30/100 passages, 300 engagements, 30 s)")
    assert lines[-1].startswith("pass 2/4: 100 % (99.9/100 passages")


def test_totals_may_grow_and_close_is_idempotent():
    out = io.StringIO()
    p = Progress("machine and cut", 2.0, "s of machine time", stream=out, interactive=False)
    p.update_to(1.0)  # 50 %
    p.set_total(4.0)
    p.update_to(1.1)  # 27 %: below the steps already printed, no line
    p.update_to(4.5)  # beyond the total
    p.close()
    p.close()
    lines = out.getvalue().splitlines()
    assert [x.split(":")[1].split("%")[0].strip() for x in lines] == ["50", "100"]
    zero = io.StringIO()
    Progress("empty", 0, stream=zero, interactive=False).close()
    assert zero.getvalue().startswith("empty: 100 %")


def test_unchanged_values_print_nothing_new():
    out = io.StringIO()
    p = Progress("x", 10, stream=out, interactive=False)
    for _ in range(50):
        p.update_to(0.0)
    assert len(out.getvalue().splitlines()) == 1  # the 0 % line once


class FakeTty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_terminal_gets_a_bar_unless_ci_says_otherwise(monkeypatch):
    monkeypatch.delenv("CI", raising=False)
    monkeypatch.setenv("TERM", "xterm")
    assert is_interactive(FakeTty()) and not is_interactive(io.StringIO())
    tty = FakeTty()
    with Progress("cut", 10, "passages", stream=tty) as p:
        for k in range(11):
            p.update_to(k)
    assert "\r" in tty.getvalue() and "10 %" not in tty.getvalue()
    monkeypatch.setenv("CI", "true")
    assert not is_interactive(FakeTty())
    s = io.StringIO()
    stage("measurement", s)
    assert s.getvalue() == "measurement ...\n"
