"""report.html of a parameter study: the page an engineer reads to learn which machine part limits the gear's
ISO 1328-1 class, by how much each part moves each parameter, and what tolerance the limiting part needs.

The answer comes first (the limiting parameter and part, the target class if one was asked for), then the
error budget per parameter, the tornado charts, and every case. Like the run's report.html it is
self-contained (charts embedded as PNG data, no script, no external resource) and uses the same style.
"""

from __future__ import annotations

import html
import io
import math
from pathlib import Path
from typing import Any

from virtual_machine.output.report import html_table, image_tag, write_page
from virtual_machine.studies.budget import Budget, ParameterBudget
from virtual_machine.studies.spec import Study

PER_FIGURE = 10  # tornado subplots per PNG
LOW_COLOUR, HIGH_COLOUR = "tab:blue", "tab:orange"
RESIDUAL = "residual (nonlinear, interactions)"


def write_study_report(
    path: Path,
    study: Study,
    records: dict[str, dict[str, Any]],
    budget: Budget,
    total_cases: int,
    wall_s: float,
    workers: int,
    cache: Path | None = None,
) -> Path:
    """Write the study's page to ``path`` (records: case id -> result.json of the finished cases; ``cache``: the
    case store the study took its reused cases from)."""
    title = f"skive study: {study.name}"
    body = [
        f"<h1>{_e(title)}</h1>",
        _summary(study, records, total_cases, wall_s, workers, cache),
        "<h2>What was varied</h2>",
        _varies_table(study),
        "<h2>Which part limits the class</h2>",
        *_limiting(study, budget),
        "<h2>Error budget</h2>",
        *_budget_tables(study, budget),
        "<h2>Tornado: each part's effect on each parameter</h2>",
        *_tornado_section(study, budget),
        "<h2>Cases</h2>",
        _cases_table(study, records),
    ]
    return write_page(path, title, body)


# --- sections ---------------------------------------------------------------------------------------------------


def _summary(
    study: Study, records: dict[str, dict[str, Any]], total: int, wall_s: float, workers: int, cache: Path | None
) -> str:
    ok = sum(r.get("status") == "ok" for r in records.values())
    failed = len(records) - ok
    reused = sorted(cid for cid, r in records.items() if r.get("reused"))
    parts = [
        f"Method <b>{_e(study.method)}</b>",
        f"base job <code>{_e(str(study.base_path))}</code>",
        f"cases: {ok} ok, {failed} failed, {total} in the design"
        + (f" ({total - len(records)} not finished)" if len(records) < total else ""),
        f"workers: {workers}" if workers else "no case ran now (every case had finished before or was reused)",
        f"wall time {_e(_duration(wall_s))}",
    ]
    if study.method == "monte-carlo":
        parts.append(f"{study.samples} samples, seed {study.seed}")
    if reused:
        store = f" <code>{_e(str(cache))}</code>" if cache else ""
        parts.append(f"{len(reused)} reused from the case store{store} (not run again): {_e(', '.join(reused))}")
    return "<p>" + "; ".join(parts) + ".</p>"


def _varies_table(study: Study) -> str:
    rows = [
        [
            v.label,
            v.key,
            _value(v.base),
            v.describe(),
            _value(v.tolerance) if v.tolerance is not None else "not stated",
        ]
        for v in study.varies
    ]
    return html_table(["part", "key", "base value", "studied values or distribution", "stated tolerance"], rows)


def _limiting(study: Study, budget: Budget) -> list[str]:
    """The answer: the parameter with the worst class at the stacked values and its largest contributor; the
    target class table if one was asked for."""
    if budget.iso_error is not None:
        out = [
            '<p class="verdict">The gear is outside ISO 1328-1\'s range: no class can be given.</p>',
            f"<p>{_e(budget.iso_error)}</p>",
        ]
    else:
        out = [_limiting_text(study, budget), *_class_counts(study, budget)]
    if budget.target is not None:
        out += _target_table(study, budget)
    return out


def _class_counts(study: Study, budget: Budget) -> list[str]:
    """The cases' classes (a Monte-Carlo study's population of machines and cutters): how many made each, and the
    share at or better than the target class."""
    if study.method != "monte-carlo" or not budget.class_counts:
        return []
    n = sum(budget.class_counts.values())
    rows = "".join(
        f"<tr><td>{'worse than 11' if c > 11 else c}</td><td>{k}</td><td>{budget.p_at_most(c):.2f}</td></tr>"
        for c, k in budget.class_counts.items()
    )
    return [
        f"<h3>The cases' classes ({n} cases)</h3>",
        f"<table><tr><th>ISO 1328-1 class</th><th>cases</th><th>share at this class or better</th></tr>{rows}</table>",
        image_tag(class_histogram_png(budget), "the cases' classes"),
    ]


def class_histogram_png(budget: Budget) -> bytes:
    """The cases' ISO 1328-1 classes as a histogram (bars: cases per class) with the share at each class or better
    (the line: P(class <= N)), the target class marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    classes = sorted(budget.class_counts)
    fig, ax = plt.subplots(figsize=(6.5, 3.0))
    ax.bar([str(c) if c <= 11 else ">11" for c in classes], [budget.class_counts[c] for c in classes], color="0.6")
    ax.set_xlabel("ISO 1328-1 class")
    ax.set_ylabel("cases")
    twin = ax.twinx()
    twin.plot(range(len(classes)), [budget.p_at_most(c) for c in classes], "o-", color="tab:blue")
    twin.set_ylim(0, 1.05)
    twin.set_ylabel("P(class <= N)", color="tab:blue")
    if budget.target is not None and budget.target in classes:
        ax.axvline(classes.index(budget.target), color="tab:red", ls="--", lw=1)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    plt.close(fig)
    return buf.getvalue()


def _limiting_text(study: Study, budget: Budget) -> str:
    found = budget.limiting()
    if found is None:
        return (
            '<p class="verdict">No parameter could be evaluated</p><p>No case finished ok'
            + (", or the base case failed" if study.method == "one-at-a-time" else " (or too few for the fit)")
            + ": see the cases below.</p>"
        )
    worst, part = found
    verdict = (
        f"{worst.name} limits the class: {worst.stacked:.2f} um ({_stacked_phrase(study)}), "
        f"{_class_text(worst.stacked_class)}."
    )
    if part is None:
        detail = "No varied part has a stated tolerance, so none is stacked: the tornado shows each part's effect."
    else:
        detail = f"Its largest contributor: <b>{_e(part.label)}</b> ({part.contribution:.2f} um)."
    return f'<p class="verdict">{_e(verdict)}</p><p>{detail}</p>'


def _target_table(study: Study, budget: Budget) -> list[str]:
    mc = study.method == "monte-carlo"
    answered = [p for p in budget.parameters if p.answer is not None]
    head = f"<h3>Target: ISO 1328-1 class {budget.target} (rows that miss it shaded)</h3>"
    if not answered:
        return [head, "<p>No parameter could be graded against the target.</p>"]
    rows, fails = [], set()
    for k, p in enumerate(answered):
        a = p.answer
        assert a is not None
        rows.append(
            [
                p.name,
                _num(a.tolerance, ".2f"),
                _num(p.base, ".2f"),
                _num(p.stacked, ".2f"),
                "yes" if a.meets else "no",
                a.limiting or "-",
                _num(a.required, ".3g"),
                a.note,
            ]
        )
        if not a.meets:
            fails.add(k)
    header = [
        "parameter",
        f"ISO tolerance, class {budget.target} [um]",
        "mean of the cases [um]" if mc else "base [um]",
        ("95th percentile of the cases" if mc else "worst case at the stated tolerances") + " [um]",
        "meets",
        "limiting part",
        "required std" if mc else "required tolerance",
        "note",
    ]
    return [head, html_table(header, rows, fails)]


def _budget_tables(study: Study, budget: Budget) -> list[str]:
    if not budget.parameters:
        return ["<p>No parameter could be evaluated.</p>"]
    mc = study.method == "monte-carlo"
    intro = (
        "<p>Monte Carlo: sensitivities from a linear least-squares fit over every case; contribution = "
        "|sensitivity| x the part's standard deviation; share = the part's share of the parameter's variance.</p>"
        if mc
        else "<p>Contribution = |sensitivity| x the part's stated tolerance, stacked arithmetically on the base "
        "value (worst case); share = the part's share of the stacked tolerances.</p>"
    )
    out = [intro]
    for p in budget.parameters:
        out += [f"<h3>{_e(p.name)}</h3>", f"<p>{_e(_parameter_line(study, p))}</p>", _parameter_table(mc, p)]
    return out


def _parameter_line(study: Study, p: ParameterBudget) -> str:
    base = "mean of the cases" if study.method == "monte-carlo" else "base"
    return f"{base} {_num(p.base, '.2f')} um; {_stacked_phrase(study)} {_num(p.stacked, '.2f')} um, " + _class_text(
        p.stacked_class
    )


def _parameter_table(mc: bool, p: ParameterBudget) -> str:
    rows = [
        [
            e.label,
            _num(e.sensitivity, ".4g"),
            _num(e.tolerance, ".4g") if e.tolerance is not None or mc else "not stated",
            _num(e.contribution, ".2f"),
            _percent(e.share),
        ]
        for e in p.parts
    ]
    if mc:
        rows.append([RESIDUAL, "", "", "", _percent(p.residual_share)])
    header = ["part", "sensitivity [um per unit]", "std" if mc else "tolerance", "contribution [um]", "share [%]"]
    return html_table(header, rows)


def _tornado_section(study: Study, budget: Budget) -> list[str]:
    if not budget.parameters:
        return ["<p>No parameter could be evaluated: no chart.</p>"]
    at = "-1 / +1 standard deviation" if study.method == "monte-carlo" else "the lowest / highest studied value"
    note = (
        f"<p>Each bar runs from the parameter's base value (vertical line) to its value with the part at {at}, "
        "every other part at its base; the parts with the widest span on top.</p>"
    )
    return [note, *(image_tag(png, "tornado") for png in tornado_pngs(study.method, budget.parameters))]


def _cases_table(study: Study, records: dict[str, dict[str, Any]]) -> str:
    rows, fails = [], set()
    for k, cid in enumerate(sorted(records)):
        r = records[cid]
        measured = r.get("measured") or {}
        values = r.get("values") or {}
        error = (r.get("error") or "").splitlines()
        rows.append(
            [
                cid,
                *(_value(values.get(v.key)) for v in study.varies),
                r.get("status", "-") + (" (reused)" if r.get("reused") else ""),
                _value(measured.get("class")),
                _num(measured.get("sync_rms_um"), ".2f"),
                _num(r.get("wall_s"), ".1f"),
                error[0] if error and r.get("status") != "ok" else "",
            ]
        )
        if r.get("status") != "ok":
            fails.add(k)
    header = ["case", *(v.label for v in study.varies), "status", "class", "sync RMS [um]", "wall [s]", "error"]
    return html_table(header, rows, fails)


# --- tornado charts ---------------------------------------------------------------------------------------------


def tornado_pngs(method: str, params: list[ParameterBudget]) -> list[bytes]:
    """The tornado charts as PNG data, up to PER_FIGURE parameters (subplots) per figure."""
    return [_tornado_png(method, params[i : i + PER_FIGURE]) for i in range(0, len(params), PER_FIGURE)]


def _tornado_png(method: str, params: list[ParameterBudget]) -> bytes:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    ncols = 1 if len(params) == 1 else 2
    nrows = math.ceil(len(params) / ncols)
    most = max((len(p.parts) for p in params), default=1)
    height = nrows * (1.1 + 0.28 * max(most, 1)) + 0.4
    fig, axes = plt.subplots(nrows, ncols, figsize=(11 if ncols == 2 else 6.5, height), squeeze=False)
    for ax, p in zip(axes.flat, params, strict=False):
        _tornado_axis(ax, p)
    for ax in list(axes.flat)[len(params) :]:
        ax.set_visible(False)
    low, high = ("-1 std", "+1 std") if method == "monte-carlo" else ("lowest studied value", "highest studied value")
    handles = [
        Patch(color=LOW_COLOUR, label=f"part at its {low}"),
        Patch(color=HIGH_COLOUR, label=f"part at its {high}"),
        Line2D([], [], color="k", lw=0.8, label="base"),
    ]
    fig.legend(handles=handles, loc="upper center", ncol=3, fontsize=8, frameon=False)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.35 / height))
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    plt.close(fig)
    return buf.getvalue()


def _tornado_axis(ax: Any, p: ParameterBudget) -> None:
    """Horizontal bars from the base value to the parameter at the part's low and high value."""
    base = p.base if math.isfinite(p.base) else 0.0
    bars = []
    for e in p.parts:
        lo, hi = _finite(e.low[1], base), _finite(e.high[1], base)
        bars.append((max(base, lo, hi) - min(base, lo, hi), e.label, lo, hi))
    bars.sort(key=lambda b: b[0])  # widest last: on top
    for y, (_, _, lo, hi) in enumerate(bars):
        ends = sorted([(lo, LOW_COLOUR), (hi, HIGH_COLOUR)], key=lambda t: -abs(t[0] - base))
        for end, colour in ends:  # the longer bar first, the shorter drawn over it
            ax.barh(y, end - base, left=base, height=0.6, color=colour)
    ax.axvline(base, color="k", lw=0.8)
    ax.set_yticks(range(len(bars)), [_plain_text(b[1]) for b in bars], fontsize=8)
    if not bars:
        ax.text(0.5, 0.5, "no numeric part", transform=ax.transAxes, ha="center", va="center", fontsize=8)
    ax.set_ylim(-0.6, max(len(bars), 1) - 0.4)
    ax.set_xlabel(f"{_plain_text(p.name)} [um]", fontsize=8)
    ax.set_title(_plain_text(p.name), fontsize=9)
    ax.tick_params(axis="x", labelsize=8)


# --- formatting -------------------------------------------------------------------------------------------------


def _e(text: str) -> str:
    return html.escape(text)


def _stacked_phrase(study: Study) -> str:
    return "95th percentile of the cases" if study.method == "monte-carlo" else "worst case at the stated tolerances"


def _class_text(c: int | None) -> str:
    return f"class {c}" if c is not None else "worse than class 11"


def _num(x: Any, spec: str) -> str:
    """A number in ``spec``; None, nan and non-numbers as "-"."""
    if x is None or isinstance(x, bool) or not isinstance(x, int | float) or not math.isfinite(x):
        return "-"
    return format(x, spec)


def _percent(share: float | None) -> str:
    return _num(None if share is None else 100.0 * share, ".1f")


def _value(v: Any) -> str:
    """A job value as the study file would write it; None and nan as "-"."""
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return f"{v:g}"
    return str(v)


def _finite(x: Any, default: float) -> float:
    return float(x) if isinstance(x, int | float) and math.isfinite(x) else default


def _duration(s: float) -> str:
    if not math.isfinite(s):
        return "-"
    if s < 120:
        return f"{s:.1f} s"
    if s < 7200:
        return f"{int(s // 60)} min {int(s % 60):02d} s"
    return f"{int(s // 3600)} h {int(s % 3600 // 60):02d} min"


def _plain_text(text: str) -> str:
    """Text for matplotlib without mathtext ($ escaped)."""
    return text.replace("$", r"\$")
