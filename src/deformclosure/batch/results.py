"""Reading a results file back: :func:`read_results` (rows, reports parsed, checked),
:func:`result_summary` (the key figures of a report) and :func:`format_results` (a text
table, CSV with units in the column names, or JSON)."""

from __future__ import annotations

import csv
import io
import math
import os
import shlex
from pathlib import Path
from typing import Any, Sequence

from ..errors import BatchError
from .store import decode_row, is_num as _is_num, iso as _iso, read_rows

__all__ = ["read_results", "result_summary", "format_results", "CSV_COLUMNS", "CSV_FIGURES"]


def read_results(db_path: str | os.PathLike, status: str | None = None) -> list[dict]:
    """Rows of a results file, sorted by part, command and options.

    Parameters
    ----------
    db_path : path-like
        Results file written by :func:`~deformclosure.batch.run_batch`.
    status : {"ok", "failed"}, optional
        Only rows with this stored status.

    Returns
    -------
    list of dict
        One dict per job with the columns of :data:`~deformclosure.batch.SCHEMA`;
        ``options`` is a list and ``result`` the parsed JSON report (``None`` for a
        failed job). Stored values are read as untrusted: JSON by the strict reader's
        rules (no NaN or Infinity, bounded nesting and integers), numbers finite, text
        UTF-8. A row that breaks them comes back with ``status = "unreadable"``,
        ``result = None`` and the reason in ``error`` — it never raises.

    Raises
    ------
    BatchError
        Missing file, not a results file, or a corrupt one.
    """
    if status not in (None, "ok", "failed"):
        raise BatchError(f"status = {status!r}: choose 'ok', 'failed' or None")
    shown = os.fspath(db_path)
    out = [decode_row(r) for r in read_rows(Path(shown), shown, status)]
    out.sort(key=lambda d: (d["part"], d["command"], d["options"], d["key"]))
    return out


#: Scalar fields of the reports shown by ``results`` (SI units, SPEC §5).
_SCALARS = ("model", "verdict", "converged", "sigma_star", "quality", "U_A", "U_L", "sigma_L",
            "force", "stiffness", "deform_closure", "order", "energy")
_FIELDS = (*_SCALARS, "quality_error", "n_pairs", "top_a", "top_b", "n_axes", "top_angle", "top_point",
           "top_sigma_star", "top_quality", "top_verdict", "n_nodes", "n_triangles")
_TEXT = frozenset({"model", "verdict", "top_verdict"})
_BOOL = frozenset({"deform_closure", "converged"})
_INT = frozenset({"order"})


def _typed(key: str, v: Any) -> Any:
    """``v`` if it has the type field ``key`` should have (stored reports are not
    trusted), else None."""
    if key in _TEXT:
        return v[:100] if isinstance(v, str) else None
    if key in _BOOL:
        return v if isinstance(v, bool) else None
    if key in _INT:
        return v if isinstance(v, int) and not isinstance(v, bool) else None
    return v if _is_num(v) else None


def _node(v: Any) -> int | None:
    return v if isinstance(v, int) and not isinstance(v, bool) else None


def _xy(v: Any) -> tuple[float, float] | None:
    if isinstance(v, list) and len(v) == 2 and all(_is_num(c) for c in v):
        return float(v[0]), float(v[1])
    return None


def _two_xy(v: Any) -> tuple[tuple[float, float], tuple[float, float]] | None:
    if isinstance(v, list) and len(v) == 2:
        a, b = _xy(v[0]), _xy(v[1])
        if a is not None and b is not None:
            return a, b
    return None


def result_summary(result: dict | None) -> dict:
    """The key scalar fields of a job's JSON report, flat.

    Parameters
    ----------
    result : dict or None
        A report of ``optimize`` (``model``, ``verdict``, ``sigma_star``, ``quality``,
        ``U_A``, ``U_L``, ``sigma_L``; pads also ``force`` (N) and ``stiffness`` (N/m)),
        ``check`` (``deform_closure``, ``order``,
        ``energy``), ``plan`` (paper: ``n_pairs`` and the best pair: ``top_a``, ``top_b``,
        ``top_sigma_star``, ``top_quality``; pads: ``n_axes`` and the best axis:
        ``top_angle`` (rad), ``top_point`` ("x y", m), ``top_sigma_star``, ``top_quality``)
        or ``mesh`` (``n_nodes``, ``n_triangles``).

    Returns
    -------
    dict
        The fields present, SI units (m, J). A field of the wrong type (a stored report
        is not trusted) is None.
    """
    if not isinstance(result, dict):
        return {}
    out = {k: _typed(k, result[k]) for k in _SCALARS
           if k in result and not isinstance(result[k], (dict, list))}
    err = result.get("error_estimate")
    if isinstance(err, dict) and "quality" in err:     # refined to --rtol (SPEC §6)
        out["quality_error"] = _typed("quality", err["quality"])
    axes = result.get("axes")
    if isinstance(axes, list):                   # a pad plan: grasp axes, verified first
        out["n_axes"] = len(axes)
        # only a verified row is a result; a screened one is a candidate (SPEC §6 "Plan")
        verified = [a for a in axes if isinstance(a, dict) and a.get("verified") is True]
        if verified:
            top = verified[0]
            out.update(top_angle=_typed("angle", top.get("angle")),
                       top_sigma_star=_typed("sigma_star", top.get("sigma_star")),
                       top_quality=_typed("quality", top.get("quality")),
                       top_verdict=_typed("verdict", top.get("verdict")))
            point = _xy(top.get("point"))
            if point is not None:
                out["top_point"] = " ".join(f"{v:.6g}" for v in point)
    pairs = result.get("pairs")
    if isinstance(pairs, list):
        out["n_pairs"] = len(pairs)
        # the plan's proposal: its `top` list (pulling pairs excluded), else the best row
        ranked = result.get("top") if isinstance(result.get("top"), list) and result["top"] \
            else pairs
        if ranked and isinstance(ranked[0], dict):
            top = ranked[0]
            out.update(top_a=_node(top.get("a")), top_b=_node(top.get("b")),
                       top_sigma_star=_typed("sigma_star", top.get("sigma_star")),
                       top_quality=_typed("quality", top.get("quality")))
    if isinstance(result.get("nodes"), list) and isinstance(result.get("triangles"), list):
        out.update(n_nodes=len(result["nodes"]), n_triangles=len(result["triangles"]))
    return out


#: Units of the summary fields, as suffixes of the CSV columns.
_UNITS = {"sigma_star": "m", "quality": "J", "U_A": "J", "U_L": "J", "sigma_L": "m",
          "force": "N", "stiffness": "N_per_m", "quality_error": "J",
          "energy": "J", "top_sigma_star": "m", "top_quality": "J", "top_angle": "rad"}
#: Columns of ``results --format csv`` after the row's own columns, in this order (those
#: present in some row). Lengths in m, energies in J, angles in rad.
CSV_FIGURES = (
    "model", "verdict", "converged", "sigma_star_m", "quality_J", "quality_error_J", "U_A_J", "U_A_infinite", "U_L_J",
    "sigma_L_m", "force_N", "stiffness_N_per_m", "jaw_a", "jaw_b", "jaw_a_x_m", "jaw_a_y_m",
    "jaw_b_x_m", "jaw_b_y_m",
    "axis_x_m", "axis_y_m", "axis_angle_rad", "deform_closure", "order", "energy_J",
    "n_pairs", "top_a", "top_b", "n_axes", "top_angle_rad", "top_point_x_m", "top_point_y_m",
    "top_jaw_a_x_m", "top_jaw_a_y_m", "top_jaw_b_x_m", "top_jaw_b_y_m", "top_sigma_star_m",
    "top_quality_J", "top_verdict", "n_nodes", "n_triangles")
#: The row's own columns in the CSV: times ISO 8601 UTC, run time in s.
CSV_COLUMNS = ("key", "part", "command", "options", "status", "error", "started_utc",
               "finished_utc", "seconds_s", "version")


def _jaw_columns(prefix: str, xy) -> dict:
    if xy is None:
        return {}
    (ax, ay), (bx, by) = xy
    return {f"{prefix}jaw_a_x_m": ax, f"{prefix}jaw_a_y_m": ay,
            f"{prefix}jaw_b_x_m": bx, f"{prefix}jaw_b_y_m": by}


def _csv_figures(result: Any) -> dict:
    """The CSV figure columns of a report (see :data:`CSV_FIGURES`): the summary with
    units in the names, and the jaw/contact coordinates the report holds."""
    if not isinstance(result, dict):
        return {}
    out = {}
    for k, v in result_summary(result).items():
        if k != "top_point":
            out[f"{k}_{_UNITS[k]}" if k in _UNITS else k] = v
    if isinstance(result.get("U_A_infinite"), bool):
        out["U_A_infinite"] = result["U_A_infinite"]
    jaws = result.get("jaws")
    if isinstance(jaws, list) and len(jaws) == 2 and all(_node(j) is not None for j in jaws):
        out.update(jaw_a=jaws[0], jaw_b=jaws[1])                  # paper model: node ids
    out.update(_jaw_columns("", _two_xy(result.get("jaw_positions"))
                            or _two_xy(result.get("contacts"))))
    axis = result.get("axis")
    if isinstance(axis, dict) and _xy(axis.get("point")) is not None:
        (x, y), angle = _xy(axis["point"]), axis.get("angle")
        out.update(axis_x_m=x, axis_y_m=y, axis_angle_rad=angle if _is_num(angle) else None)
    for kind in ("axes", "pairs"):                                 # a plan: the best grasp
        best = result.get(kind)
        if kind == "pairs" and isinstance(result.get("top"), list) and result["top"]:
            best = result["top"]                        # paper plans: pulling pairs excluded
        if kind == "axes" and isinstance(best, list):   # pad plans: verified rows only
            best = [a for a in best if isinstance(a, dict) and a.get("verified") is True]
        if isinstance(best, list) and best and isinstance(best[0], dict):
            top = best[0]
            point = _xy(top.get("point"))
            if point is not None:
                out.update(top_point_x_m=point[0], top_point_y_m=point[1])
            out.update(_jaw_columns("top_", _two_xy(top.get("jaw_positions"))
                                    or _two_xy(top.get("contacts"))))
    return out


def _describe(row: dict) -> str:
    if row["status"] == "unreadable":
        return f"unreadable row: {row.get('error')}"
    if row["status"] != "ok":
        return f"error: {row['error']}"
    s = result_summary(row["result"])

    def g(v, u=""):
        return "-" if v is None else (f"{v:.4g}{u}" if isinstance(v, float) else f"{v}{u}")

    if "n_axes" in s:
        if s.get("top_angle") is None:
            return f"{s['n_axes']} axes"
        return (f"best verified axis {math.degrees(s['top_angle']):.1f} deg through "
                f"({s.get('top_point')}) m sigma*={g(s.get('top_sigma_star'), ' m')} "
                f"Q={g(s.get('top_quality'), ' J')} {s.get('top_verdict')} ({s['n_axes']} axes)")
    if "top_quality" in s or "n_pairs" in s:
        if "top_a" not in s:
            return f"{s['n_pairs']} pairs"
        return (f"best {g(s['top_a'])}-{g(s['top_b'])} sigma*={g(s.get('top_sigma_star'), ' m')} "
                f"Q={g(s.get('top_quality'), ' J')} ({s['n_pairs']} pairs)")
    if "sigma_star" in s or "quality" in s:
        v = f" {s['verdict']}" if s.get("verdict") else ""
        F = f" F={g(s['force'], ' N')}" if s.get("force") is not None else ""
        return f"sigma*={g(s.get('sigma_star'), ' m')} Q={g(s.get('quality'), ' J')}{F}{v}"
    if "deform_closure" in s:
        dc = s["deform_closure"]
        return f"deform closure: {'-' if dc is None else 'yes' if dc else 'no'}, order {g(s.get('order'))}"
    if "n_nodes" in s:
        return f"{s['n_nodes']} nodes, {s['n_triangles']} triangles"
    return "ok"


def _csv_cell(v: Any) -> Any:
    return "" if v is None else v


def format_results(rows: Sequence[dict], fmt: str = "table") -> str:
    """Render rows of :func:`read_results` as a text table, CSV or JSON.

    Parameters
    ----------
    rows : sequence of dict
    fmt : {"table", "csv", "json"}
        ``table``: one line per job (part, command, status, key figures, seconds) and a
        count. ``csv``: the row's columns (:data:`CSV_COLUMNS`: ``options``
        shell-quoted, ``started_utc``/``finished_utc`` ISO 8601 UTC, ``seconds_s``) and
        the figures of the report with their units in the names (:data:`CSV_FIGURES`:
        ``sigma_star_m``, ``quality_J``, the jaw or contact coordinates in m, ...).
        ``json``: a list of the full rows, reports included.

    Returns
    -------
    str
    """
    if fmt == "json":
        from ..outputs import json_text

        return json_text(list(rows))
    if fmt == "csv":
        return _csv_text(rows)
    if fmt != "table":
        raise BatchError(f"format = {fmt!r}: choose 'table', 'csv' or 'json'")
    return _table_text(rows)


def _csv_text(rows: Sequence[dict]) -> str:
    """``results --format csv``: :data:`CSV_COLUMNS`, then the :data:`CSV_FIGURES` present."""
    figures = [_csv_figures(r.get("result")) for r in rows]
    present = set().union(*figures) if figures else set()
    fields = [f for f in CSV_FIGURES if f in present]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow([*CSV_COLUMNS, *fields])
    for r, fig in zip(rows, figures):
        own = {"key": r.get("key"), "part": r.get("part"), "command": r.get("command"),
               "options": shlex.join(r.get("options") or []), "status": r.get("status"),
               "error": r.get("error"), "started_utc": _iso(r.get("started")),
               "finished_utc": _iso(r.get("finished")),
               "seconds_s": r.get("seconds") if _is_num(r.get("seconds")) else None,
               "version": r.get("version")}
        w.writerow([_csv_cell(own[c]) for c in CSV_COLUMNS]
                   + [_csv_cell(fig.get(f)) for f in fields])
    return buf.getvalue()


def _table_text(rows: Sequence[dict]) -> str:
    """``results``: one line per job and a count."""
    if not rows:
        return "no jobs"
    table = [(r["part"], " ".join([r["command"], *r["options"]]), r["status"],
              f"{r['seconds']:.2f}" if _is_num(r.get("seconds")) else "-", _describe(r))
             for r in rows]
    head = ("part", "command", "status", "seconds", "result (SI units)")
    wid = [min(48, max(len(t[i]) for t in [head, *table])) for i in range(4)]

    def fmt_row(t):
        cells = [f"{t[i][:wid[i]]:<{wid[i]}}" if i != 3 else f"{t[i]:>{wid[i]}}" for i in range(4)]
        return "  ".join(cells + [t[4]])

    n_ok = sum(r["status"] == "ok" for r in rows)
    n_bad = sum(r["status"] == "failed" for r in rows)
    n_unreadable = len(rows) - n_ok - n_bad
    count = f"{len(rows)} job{'s' * (len(rows) != 1)}: {n_ok} ok, {n_bad} failed"
    if n_unreadable:
        count += f", {n_unreadable} unreadable"
    lines = [fmt_row(head), *(fmt_row(t) for t in table), count]
    return "\n".join(line.rstrip() for line in lines)
