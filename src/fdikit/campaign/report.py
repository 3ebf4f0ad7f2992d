"""The HTML report of a campaign: one self-contained page from a results folder.

:func:`write_report` reads ``OUT/campaign.json`` and the results table ``OUT/runs/`` and writes
``OUT/report.html`` (atomically): the campaign summary, the per-design comparison, the per-fault tables, the
false alarms, the trade-off over the threshold sweep, the confusion matrices and the figures (PNG inlined as
``data:`` URIs), all computed by :func:`fdikit.campaign.stats.campaign_statistics`.  The page loads nothing
from elsewhere: inline CSS, no script.  With a ``replay`` callable it also draws a few interesting runs per
design × evaluator (:func:`pick_examples`) into ``OUT/report-traces/`` and links them.
"""

from __future__ import annotations

import hashlib
import html
import json
import math
import os
import re
from collections.abc import Callable
from pathlib import Path
from urllib.parse import quote

from fdikit.errors import DataError

__all__ = ["write_report", "pick_examples", "trace_file_name"]

_NONE = "none"
_CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Helvetica,Arial,sans-serif;margin:2em auto;max-width:72em;
padding:0 1em;color:#222;line-height:1.4}
h1{font-size:1.6em;border-bottom:2px solid #446;padding-bottom:.2em}h2{font-size:1.25em;margin-top:1.8em;color:#335}
h3{font-size:1.05em;margin-top:1.2em}table{border-collapse:collapse;margin:.6em 0;font-size:.85em}
th,td{border:1px solid #ccd;padding:.25em .55em;text-align:right}th{background:#eef}
td.l,th.l{text-align:left}dl.s{display:grid;grid-template-columns:max-content auto;gap:.2em 1em}
dl.s dt{font-weight:600}dl.s dd{margin:0}img{max-width:100%;height:auto}p.note{color:#555;font-size:.85em}
code{background:#f3f3f6;padding:0 .2em}
"""


def _e(x) -> str:
    return html.escape(str(x), quote=True)


def _num(x, digits: int = 3) -> str:
    try:
        x = float(x)
    except (TypeError, ValueError):
        return "—"
    if not math.isfinite(x):
        return "—"
    if x == 0:
        return "0"
    return f"{x:.{digits}g}"


def _pct(rate, lo=None, hi=None) -> str:
    if not _finite(rate):
        return "—"
    s = f"{100 * float(rate):.1f} %"
    if lo is not None and _finite(lo):
        s += f" [{100 * float(lo):.1f}, {100 * float(hi):.1f}]"
    return s


def _rate(rate, lo, hi) -> str:
    return "—" if not _finite(rate) else f"{_num(rate)} [{_num(lo)}, {_num(hi)}]"


def _finite(x) -> bool:
    try:
        return math.isfinite(float(x))
    except (TypeError, ValueError):
        return False


def _table(header: list[str], rows: list[list], left: int = 0) -> str:
    """An HTML table; the first ``left`` columns left-aligned (names); cells are escaped."""
    def cell(tag, j, v):
        cls = ' class="l"' if j < left else ""
        return f"<{tag}{cls}>{_e(v)}</{tag}>"

    head = "".join(cell("th", j, h) for j, h in enumerate(header))
    body = "".join("<tr>" + "".join(cell("td", j, v) for j, v in enumerate(r)) + "</tr>" for r in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def trace_file_name(run: int, design: str, evaluator: str) -> str:
    """File name of an example trace: ``run-<run>-<design>-<evaluator>.png`` with the names made file-safe.

    Characters other than letters, digits, ``.``, ``_`` and ``-`` become ``_``; a name that changed gets a short
    digest of the original so two names never share a file.

    Parameters
    ----------
    run : int
        The run.
    design, evaluator : str
        The design and evaluator names.

    Returns
    -------
    str
        The file name.

    Examples
    --------
    >>> trace_file_name(3, "bank", "cusum")
    'run-3-bank-cusum.png'
    >>> trace_file_name(3, "a/b", "x y")
    'run-3-a_b~3ec69c-x_y~73dec5.png'
    """
    def safe(name: str) -> str:
        s = re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip(".") or "_"
        return s if s == name else f"{s}~{hashlib.sha1(name.encode()).hexdigest()[:6]}"

    return f"run-{int(run)}-{safe(str(design))}-{safe(str(evaluator))}.png"


def pick_examples(table, examples: int = 2) -> list[dict]:
    """Interesting runs per design × evaluator: a missed detection, a false alarm, the slowest detection.

    In that order, up to ``examples`` distinct runs per pair: the missed faulty run of lowest index; the run
    with the most false alarms (fault-free runs first, then the lowest index); the detected run with the longest
    detection delay (then the lowest index).  The choice depends on the table only.

    Parameters
    ----------
    table : pandas.DataFrame
        Results rows (``run``, ``design``, ``evaluator``, ``fault``, ``missed``, ``detected``, ``detection_delay``,
        ``false_alarms``, ``onset``).
    examples : int, default 2
        Runs per design × evaluator, ``>= 0``.

    Returns
    -------
    list of dict
        ``design``, ``evaluator``, ``run``, ``reason``, ``fault``, ``onset`` (None when fault-free),
        ``detection_delay``, ``false_alarms``; sorted by design, evaluator, then the order above.

    Examples
    --------
    >>> import pandas as pd
    >>> t = pd.DataFrame(dict(run=[0, 1, 2], design="a", evaluator="e", fault=["none", "f", "f"],
    ...                       missed=[False, True, False], detected=[False, False, True],
    ...                       detection_delay=[float("nan"), float("nan"), 2.0], false_alarms=[1, 0, 0],
    ...                       onset=[float("nan"), 5.0, 5.0]))
    >>> [(x["run"], x["reason"]) for x in pick_examples(t, 3)]
    [(1, 'missed detection'), (0, 'false alarm'), (2, 'slowest detection')]
    """
    from fdikit import validate

    examples = validate.integer("examples", examples, minimum=0)
    out = []
    if examples == 0 or len(table) == 0:
        return out
    df = table.reset_index(drop=True)
    for (design, evaluator), g in df.groupby(["design", "evaluator"], sort=True):
        g = g.assign(_free=(g["fault"] == _NONE), _run=g["run"].astype(int))
        faulty = g[~g["_free"]]
        picks = []
        missed = faulty[faulty["missed"].astype(bool)].sort_values("_run")
        if len(missed):
            picks.append((missed.iloc[0], "missed detection"))
        fa = g[g["false_alarms"] > 0].sort_values(["_free", "false_alarms", "_run"], ascending=[False, False, True])
        if len(fa):
            picks.append((fa.iloc[0], "false alarm"))
        det = faulty[faulty["detected"].astype(bool) & faulty["detection_delay"].notna()]
        det = det.sort_values(["detection_delay", "_run"], ascending=[False, True])
        if len(det):
            picks.append((det.iloc[0], "slowest detection"))
        seen = set()
        for row, reason in picks:
            if row["_run"] in seen or len(seen) >= examples:
                continue
            seen.add(row["_run"])
            onset = float(row["onset"]) if _finite(row["onset"]) and not row["_free"] else None
            out.append({"design": str(design), "evaluator": str(evaluator), "run": int(row["_run"]),
                        "reason": reason, "fault": str(row["fault"]), "onset": onset,
                        "detection_delay": float(row["detection_delay"]) if _finite(row["detection_delay"]) else None,
                        "false_alarms": int(row["false_alarms"])})
    return out


def _load(folder: Path):
    import pandas as pd

    meta_path = folder / "campaign.json"
    try:
        meta = json.loads(meta_path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise DataError(f"{meta_path} not found; give a campaign's results folder") from None
    except (OSError, ValueError) as exc:
        raise DataError(f"cannot read {meta_path}: {exc}") from exc
    if not isinstance(meta, dict) or "levels" not in meta:
        raise DataError(f"{meta_path} has no 'levels' (the sweep levels); is it a campaign.json?")
    runs = folder / "runs"
    if not runs.is_dir() or not any(runs.glob("*.parquet")):
        raise DataError(f"{runs} holds no Parquet chunks; the campaign has no results yet")
    try:
        table = pd.read_parquet(runs)
    except Exception as exc:  # pyarrow raises several types for a damaged dataset
        raise DataError(f"cannot read the results in {runs}: {exc}") from exc
    return meta, table


def _summary(meta: dict, table) -> str:
    designs = meta.get("designs") or sorted({str(d) for d in table["design"]})
    evaluators = meta.get("evaluators") or sorted({str(e) for e in table["evaluator"]})
    runs = meta.get("runs", table["run"].nunique() if "run" in table else len(table))
    duration = meta.get("duration")
    items = [("name", meta.get("name", "")), ("runs", f"{runs} ({len(table)} result rows)"),
             ("designs", ", ".join(map(str, designs))), ("evaluators", ", ".join(map(str, evaluators))),
             ("sweep levels", ", ".join(_num(x) for x in meta.get("levels", []))),
             ("duration", f"{_num(duration)} s" if _finite(duration) else "—"),
             ("fdikit", meta.get("fdikit", "")), ("fingerprint", meta.get("fingerprint", ""))]
    body = "".join(f"<dt>{_e(k)}</dt><dd>{_e(v)}</dd>" for k, v in items)
    return f'<dl class="s">{body}</dl>'


def _comparison(st) -> str:
    rows = [[r.design, r.evaluator, r.runs, _pct(r.detection_rate, r.detection_low, r.detection_high),
             _num(r.delay_median), _num(r.delay_p90), _pct(r.isolation_rate, r.isolation_low, r.isolation_high),
             f"{r.runs_with_false_alarm} / {r.fault_free_runs}",
             _rate(r.false_alarm_rate, r.false_alarm_rate_low, r.false_alarm_rate_high)]
            for r in st.overall.itertuples(index=False)]
    return _table(["design", "evaluator", "faulty runs", "detection rate [CI]", "median delay [s]",
                   "p90 delay [s]", "isolation rate [CI]", "fault-free runs with a false alarm",
                   "false alarms / h [CI]"], rows, left=2)


def _per_fault(st) -> str:
    out = []
    for fault, g in st.detection.groupby("fault", sort=True):
        rows = [[r.design, r.evaluator, r.runs, _pct(r.detection_rate, r.detection_low, r.detection_high),
                 r.missed, _num(r.delay_median), _num(r.delay_mean), _num(r.delay_p10), _num(r.delay_p90),
                 _num(r.delay_max), _pct(r.isolation_rate, r.isolation_low, r.isolation_high),
                 _num(r.isolation_delay_median), _num(r.isolation_delay_p90)]
                for r in g.itertuples(index=False)]
        out.append(f"<h3>fault <code>{_e(fault)}</code></h3>" + _table(
            ["design", "evaluator", "runs", "detection rate [CI]", "missed", "median delay [s]", "mean [s]",
             "p10 [s]", "p90 [s]", "max [s]", "isolation rate [CI]", "median isolation delay [s]",
             "p90 isolation delay [s]"], rows, left=2))
    return "".join(out) or "<p>No faulty runs.</p>"


def _study_figures(table) -> str:
    from fdikit.campaign.stats import metric_summary

    figures = metric_summary(table)
    if figures.empty:
        return "<p>This study stores no figures of its own.</p>"
    out = []
    for (design, evaluator), g in figures.groupby(["design", "evaluator"], sort=True):
        rows = [[r.fault, r.metric, r.runs, _num(r.mean), _num(r.median), _num(r.p10), _num(r.p90), _num(r.min),
                 _num(r.max)] for r in g.itertuples(index=False)]
        out.append(f"<details><summary><code>{_e(design)}</code> / <code>{_e(evaluator)}</code> "
                   f"({len(rows)} figures)</summary>" + _table(
                       ["fault", "figure", "runs", "mean", "median", "p10", "p90", "min", "max"], rows, left=2)
                   + "</details>")
    return "".join(out)


def _false_alarms(st) -> str:
    rows = [[r.design, r.evaluator, r.fault_free_runs, r.runs_with_false_alarm,
             _pct(r.false_alarm_run_fraction, r.false_alarm_run_low, r.false_alarm_run_high), r.false_alarms,
             _num(r.fault_free_hours, 4), _rate(r.false_alarm_rate, r.false_alarm_rate_low, r.false_alarm_rate_high)]
            for r in st.false_alarms.itertuples(index=False)]
    return _table(["design", "evaluator", "fault-free runs", "with ≥ 1 false alarm", "fraction [CI]",
                   "false alarms (all fault-free time)", "fault-free hours", "false alarms / h [CI]"], rows, left=2)


def _tradeoff(st) -> str:
    rows = [[r.design, r.evaluator, _num(r.level), r.false_alarms,
             _rate(r.false_alarm_rate, r.false_alarm_rate_low, r.false_alarm_rate_high),
             _pct(r.detection_rate, r.detection_low, r.detection_high), _num(r.delay_median), _num(r.delay_p90)]
            for r in st.tradeoff.itertuples(index=False)]
    return _table(["design", "evaluator", "level", "false alarms", "false alarms / h [CI]", "detection rate [CI]",
                   "median delay [s]", "p90 delay [s]"], rows, left=2)


def _confusion(st) -> str:
    out = []
    for design, evaluator in st.pairs():
        m = st.confusion_matrix(design, evaluator)
        rows = [[t, *m.loc[t].tolist()] for t in m.index]
        out.append(f"<h3>{_e(design)} / {_e(evaluator)}</h3>"
                   + _table(["true \\ diagnosed", *map(str, m.columns)], rows, left=1))
    return "".join(out) or "<p>No runs.</p>"


def _figure(fig, alt: str, empty: str) -> str:
    from fdikit.campaign.report_plots import png_data_uri

    if fig is None:
        return f"<p>{_e(empty)}</p>"
    return f'<p><img alt="{_e(alt)}" src="{png_data_uri(fig)}"></p>'


def _examples(folder: Path, out: Path, table, replay, examples: int, tick) -> str:
    from fdikit.campaign.report_plots import example_trace_figure, write_png

    if replay is None:
        return "<p>Example traces were not requested (no <code>replay</code> given).</p>"
    picks = pick_examples(table, examples)
    if not picks:
        return "<p>No example runs to show.</p>"
    traces = folder / "report-traces"
    items = []
    for p in picks:
        name = trace_file_name(p["run"], p["design"], p["evaluator"])
        what = (f"run {p['run']} — {p['design']} / {p['evaluator']}: {p['reason']} (fault {p['fault']}"
                + (f", delay {_num(p['detection_delay'])} s" if p["detection_delay"] is not None else "")
                + f", {p['false_alarms']} false alarms)")
        try:
            _trace, residuals, diagnosis = replay(p["run"], p["design"], p["evaluator"])
            fig = example_trace_figure(residuals, diagnosis, p["onset"], title=what)
            path = write_png(fig, traces / name)
        except Exception as exc:  # a failed replay is reported on the page; the rest of the report stands
            items.append(f"<li>{_e(what)}: replay failed ({_e(type(exc).__name__)}: {_e(exc)})</li>")
        else:
            href = quote(Path(os.path.relpath(path, out.parent)).as_posix())
            items.append(f'<li><a href="{_e(href)}">{_e(what)}</a></li>')
        tick(f"example run {p['run']}")
    return "<ul>" + "".join(items) + "</ul>"


def write_report(folder: str | os.PathLike, out: str | os.PathLike | None = None,
                 replay: Callable | None = None, examples: int = 2, progress: bool = False) -> Path:
    """Write the campaign's HTML report: one self-contained page (module docstring).

    Parameters
    ----------
    folder : str or PathLike
        The campaign's results folder (``campaign.json`` and ``runs/``).
    out : str or PathLike, optional
        The page; default ``folder/report.html``.  Written atomically (:func:`fdikit.atomic.write_text`).
    replay : callable, optional
        ``replay(run, design, evaluator) -> (trace, residuals, diagnosis)``: re-runs one row and returns its
        :class:`~fdikit.trace.Trace`, :class:`~fdikit.residuals.Residuals` and
        :class:`~fdikit.diagnosis.Diagnosis`.  Given, the runs of :func:`pick_examples` are drawn into
        ``folder/report-traces/`` (:func:`trace_file_name`) and linked; a replay that raises is reported on the
        page.  Without it the page says example traces were not requested.
    examples : int, default 2
        Example runs per design × evaluator.
    progress : bool, default False
        Show a rich progress bar.

    Returns
    -------
    Path
        The page.

    Raises
    ------
    DataError
        When the folder has no readable ``campaign.json`` or no results, or the table lacks columns.

    Examples
    --------
    >>> import json, math, pathlib, tempfile
    >>> import pyarrow.parquet as pq
    >>> from fdikit.campaign.schema import table_from_rows
    >>> nan = math.nan
    >>> row = dict(run=0, chunk=0, plant="p", fault="f_sensor", kind="bias", size=1.0, onset=5.0, seed=1,
    ...            design="bank", evaluator="threshold", detected=True, missed=False, detection_delay=0.5,
    ...            isolated="f_sensor", isolation_correct=True, isolation_delay=0.7, correct_fraction=1.0,
    ...            false_alarms=0, fault_free_hours=5 / 3600, sweep_delay=[0.5], sweep_false_alarms=[0],
    ...            metrics="{}")
    >>> out = pathlib.Path(tempfile.mkdtemp())
    >>> (out / "runs").mkdir()
    >>> pq.write_table(table_from_rows([row]), out / "runs" / "chunk-000000.parquet")
    >>> _ = (out / "campaign.json").write_text(json.dumps({"name": "demo", "levels": [1.0], "runs": 1}))
    >>> page = write_report(out)
    >>> page.name, "demo" in page.read_text()
    ('report.html', True)
    """
    from fdikit import validate
    from fdikit.atomic import write_text
    from fdikit.campaign.report_plots import delay_distribution_figure, detection_by_fault_figure, tradeoff_figure
    from fdikit.campaign.stats import campaign_statistics
    from fdikit.progress import progress_bar

    folder = Path(folder)
    out = folder / "report.html" if out is None else Path(out)
    examples = validate.integer("examples", examples, minimum=0)
    meta, table = _load(folder)
    st = campaign_statistics(table, meta["levels"])
    n_examples = len(pick_examples(table, examples)) if replay is not None else 0
    name = meta.get("name", folder.name)
    with progress_bar(progress, 4 + n_examples, "campaign report") as tick:
        fig_rate = _figure(detection_by_fault_figure(st.detection), "detection rate per fault", "No faulty runs.")
        tick("detection rate per fault")
        fig_delay = _figure(delay_distribution_figure(table), "detection delay distributions", "No detections.")
        tick("delay distributions")
        fig_trade = _figure(tradeoff_figure(st.tradeoff), "trade-off curves", "No fault-free time: no rates.")
        tick("trade-off curves")
        traces = _examples(folder, out, table, replay, examples, tick)
        level = f"{100 * st.confidence:g} %"
        sections = [
            f"<h1>Campaign report: {_e(name)}</h1>", _summary(meta, table),
            "<h2>Comparison of the designs</h2>",
            f"<p class=\"note\">All faults pooled. Intervals [CI] are two-sided {level}: Clopper–Pearson for "
            "rates of runs, Garwood (exact Poisson) for false alarms per hour of fault-free time (fault-free runs "
            "and the pre-onset part of faulty runs). The isolation rate counts correctly isolated faulty runs "
            "among all faulty runs (a missed run is not isolated).</p>", _comparison(st),
            "<h2>Detection rate per fault</h2>", fig_rate,
            "<h2>Detection delay distributions</h2>",
            "<p class=\"note\">Fraction of the faulty runs detected within a given delay after the onset, one panel "
            "per design; each curve levels off at its detection rate.</p>", fig_delay,
            "<h2>Trade-off over the threshold sweep</h2>",
            "<p class=\"note\">Each evaluator's threshold scaled by the sweep levels (the star is the nominal level "
            "1.0), computed from the stored sweep statistics: false alarms per hour against the median detection "
            "delay and the detection rate. A level without false alarms is drawn as an open marker at half the "
            "smallest resolvable rate.</p>", fig_trade,
            f"<details><summary>trade-off table ({len(st.tradeoff)} rows)</summary>{_tradeoff(st)}</details>",
            "<h2>Per fault</h2>", _per_fault(st),
            "<h2>Study figures</h2>",
            "<p class=\"note\">The study's own per-run figures (the <code>metrics</code> column: RMSEs, flight "
            "errors, isolation times), over the runs of each fault.</p>", _study_figures(table),
            "<h2>False alarms</h2>", _false_alarms(st),
            "<h2>Confusion matrices</h2>",
            "<p class=\"note\">Rows: true fault; columns: the isolated fault, <code>missed</code>, or "
            "<code>none</code> (a fault-free run without false alarm; with one, the fault it isolated).</p>",
            _confusion(st),
            "<h2>Example traces</h2>", traces,
            f"<p class=\"note\">Generated by fdikit {_e(meta.get('fdikit', ''))} from {_e(folder.name)}.</p>",
        ]
        page = ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                f"<title>{_e(name)} — fdikit campaign report</title><style>{_CSS}</style></head>\n<body>\n"
                + "\n".join(sections) + "\n</body></html>\n")
        write_text(out, page)
        tick("page written")
    return out
