"""The diagnosis of one log by a detector: a table and an HTML report (what ``fdikit diagnose`` writes).

Files written atomically (:mod:`fdikit.atomic`) into one folder:

* ``diagnosis.csv`` — one row per sample: time, valid, alarm, the isolated fault, each residual and
  whether it fired;
* ``alarms.csv`` — one row per alarm event (time, fault named at the alarm, residuals that fired);
* ``report.html`` — the detector, the log, the alarm events, the score against the log's truth labels
  when it has any (:func:`fdikit.metrics.score`), the residual plots with their thresholds and the
  isolated fault over time.
"""

from __future__ import annotations

import base64
import dataclasses
import html
import os
from pathlib import Path

import numpy as np

from fdikit.atomic import write_text
from fdikit.faults import NO_FAULT

__all__ = ["diagnosis_table", "write_diagnosis"]


def diagnosis_table(residuals, diagnosis):
    """The per-sample diagnosis as a DataFrame: time, valid, alarm, fault, each residual and its decision.

    Parameters
    ----------
    residuals : Residuals
        The detector's residuals of the log.
    diagnosis : Diagnosis
        Its decisions.

    Returns
    -------
    pandas.DataFrame
        Columns ``t``, ``valid``, ``alarm``, ``fault``, then ``<residual>`` and ``<residual>:fired`` per residual.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision import ThresholdEvaluator
    >>> from fdikit.residuals import Residuals
    >>> res = Residuals(np.arange(3.0), np.c_[[0.0, 2.0, 0.0]], ("r",), ("f",))
    >>> diagnosis_table(res, ThresholdEvaluator(thresholds=[1.0]).run(res))["fault"].tolist()
    ['none', 'f', 'none']
    """
    import pandas as pd

    data = {"t": residuals.t, "valid": diagnosis.valid, "alarm": diagnosis.alarm, "fault": diagnosis.isolated}
    fired = dict(zip(diagnosis.names, np.asarray(diagnosis.fired).T))
    for j, nm in enumerate(residuals.names):
        data[nm] = residuals.r[:, j]
        if nm in fired:
            data[f"{nm}:fired"] = fired[nm]
    return pd.DataFrame(data)


def _png(fig) -> str:
    from fdikit.plots import figure_bytes

    return base64.b64encode(figure_bytes(fig)).decode("ascii")


def _table(rows, header) -> str:
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>" for row in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def write_diagnosis(folder: str | os.PathLike, detector, trace, *, log_name: str = "log"):
    """Run ``detector`` on ``trace`` and write the diagnosis table, the alarm events and the HTML report.

    Parameters
    ----------
    folder : str or PathLike
        Output folder (created).
    detector : Detector
        The detector (:class:`fdikit.detector.Detector`, e.g. ``Detector.load(path)``).
    trace : Trace
        The log (``detector.read_log(path)``).
    log_name : str, default "log"
        The log's name in the report.

    Returns
    -------
    diagnosis : Diagnosis
        The detector's decisions on the trace.
    files : dict of str to Path
        ``{"diagnosis": …, "alarms": …, "report": …}``.

    Raises
    ------
    DataError
        When the trace lacks a signal the detector reads.
    OSError
        When the folder cannot be written.

    Examples
    --------
    >>> import numpy as np, tempfile
    >>> from fdikit.decision import ThresholdEvaluator
    >>> from fdikit.detector import Detector
    >>> from fdikit.residuals import ResidualGenerator
    >>> from fdikit.trace import Trace
    >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
    >>> det = Detector(g, ThresholdEvaluator(thresholds=[0.5], isolates=("y_sensor",)))
    >>> tr = Trace(np.arange(6.0), np.ones((6, 1)), np.c_[[0.0, 1.0, 1.9, 3.71, 4.439, 5.0951]], ("u",), ("y",))
    >>> diagnosis, files = write_diagnosis(tempfile.mkdtemp(), det, tr)
    >>> diagnosis.first_alarm().fault, sorted(p.name for p in files.values())
    ('y_sensor', ['alarms.csv', 'diagnosis.csv', 'report.html'])
    """
    import matplotlib.pyplot as plt
    import pandas as pd

    from fdikit.metrics import score
    from fdikit.plots import plot_diagnosis, plot_residuals

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    residuals = detector.residuals(trace)
    diagnosis = detector.run(trace)
    table = diagnosis_table(residuals, diagnosis)
    events = pd.DataFrame([(a.time, a.fault, " ".join(a.residuals)) for a in diagnosis.alarms],
                          columns=["time", "fault", "residuals"])
    paths = {"diagnosis": folder / "diagnosis.csv", "alarms": folder / "alarms.csv", "report": folder / "report.html"}
    write_text(paths["diagnosis"], table.to_csv(index=False))
    write_text(paths["alarms"], events.to_csv(index=False))

    ev = detector.evaluator   # residuals are the ones it reads, in its order (Detector.residuals)
    thresholds, center = getattr(ev, "thresholds", None), getattr(ev, "center", None)
    fig = plot_residuals(residuals, diagnosis, thresholds=thresholds, center=center, onset=trace.fault_onset,
                         title=f"{detector.name}: residuals of {log_name}")
    residual_png = _png(fig)
    plt.close(fig)
    fig = plot_diagnosis(diagnosis, title="isolated fault")
    diagnosis_png = _png(fig)
    plt.close(fig)

    named = table.loc[table["fault"] != NO_FAULT, "fault"].value_counts()
    summary = [("samples", len(trace)), ("duration [s]", f"{trace.t[-1] - trace.t[0]:g}"),
               ("invalid samples", int((~diagnosis.valid).sum())), ("alarm events", len(diagnosis.alarms)),
               ("samples in alarm", int(diagnosis.alarm.sum()))]
    summary += [(f"samples named {f}", int(c)) for f, c in named.items()]
    score_html = ""
    if np.any(trace.fault != NO_FAULT) or "fault" in trace.meta.get("import", {}):
        s = score(trace, diagnosis)
        rows = [(f.name, getattr(s, f.name)) for f in dataclasses.fields(s) if np.ndim(getattr(s, f.name)) == 0]
        score_html = "<h2>Score against the log's truth labels</h2>" + _table(rows, ("metric", "value"))
    rows_alarms = [(f"{a.time:g}", a.fault, " ".join(a.residuals)) for a in diagnosis.alarms[:200]]
    more = f"<p>… {len(diagnosis.alarms) - 200} more in alarms.csv</p>" if len(diagnosis.alarms) > 200 else ""
    page = (
        "<!doctype html><html><head><meta charset='utf-8'>"
        f"<title>fdikit diagnosis: {html.escape(detector.name)} on {html.escape(log_name)}</title>"
        "<style>body{font-family:sans-serif;max-width:1100px;margin:auto}table{border-collapse:collapse}"
        "td,th{border:1px solid #ccc;padding:2px 8px;text-align:left}img{max-width:100%}</style></head><body>"
        f"<h1>Diagnosis of {html.escape(log_name)}</h1>"
        f"<p>Detector <b>{html.escape(detector.name)}</b> ({html.escape(detector.description)}), built "
        f"{html.escape(str(detector.created))} with fdikit {html.escape(str(detector.fdikit_version))}; reads "
        f"controls {html.escape(', '.join(detector.controls))} and outputs {html.escape(', '.join(detector.outputs))}."
        "</p><h2>Summary</h2>" + _table(summary, ("", "")) + score_html
        + "<h2>Alarm events</h2>" + (_table(rows_alarms, ("time [s]", "fault", "residuals fired")) if rows_alarms
                                     else "<p>none</p>") + more
        + f"<h2>Residuals</h2><img alt='residuals' src='data:image/png;base64,{residual_png}'>"
        + f"<h2>Isolated fault</h2><img alt='isolated fault' src='data:image/png;base64,{diagnosis_png}'>"
        + "<p>Per-sample decisions: diagnosis.csv; alarm events: alarms.csv.</p></body></html>"
    )
    write_text(paths["report"], page)
    return diagnosis, paths
