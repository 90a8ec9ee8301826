"""Figures of a diagnosis (plotting only): the candidate ranking and the gap before / after.

Both read the JSON record of a diagnosis (:meth:`pipeline.diagnose.DiagnoseResult.to_json`, the
``diagnose/diagnose.json`` of a run folder), so the report draws them from the run folder alone.
Figures are built on :class:`matplotlib.figure.Figure` without pyplot (no global figure state).
"""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Patch

#: Bar colour of each effect kind (pipeline.diagnose.effects.KINDS, and "none").
KIND_COLOURS = {"lumped_mass": "tab:blue", "joint_flexibility": "tab:red",
                "member_taper": "tab:green", "member_curvature": "tab:purple",
                "boundary_stiffness": "tab:orange", "none": "0.5"}
#: The gap metrics drawn, per panel: (title, unit, [(key, label)]).
GAP_PANELS = (("frequency error", "RMS %", (("frequency_rms_held_out", "held-out modes"),
                                            ("frequency_rms_cross_validated",
                                             "every mode, cross-validated"),
                                            ("frequency_rms", "all paired modes"))),
              ("mode shapes", "MAC, |S_ij| (0 .. 1)",
               (("max_cross_orthogonality_offdiag", "largest |S_ij|, i != j"),
                ("mac_min", "smallest paired MAC"))))


def candidate_label(entry: dict) -> str:
    """A candidate's text: its ``label`` when given, else its kind and location."""
    if entry.get("label"):
        return str(entry["label"])
    where = ", ".join(f"{k} {v}" for k, v in (entry.get("location") or {}).items() if v)
    return f"{entry['kind']} ({where})" if where else str(entry["kind"])


def plot_candidates(record: dict, top: int = 12, *, ax=None) -> Figure:
    """The ranked candidates of the first round as horizontal bars of their score, with the best
    of every other kind below them.

    Parameters
    ----------
    record : dict
        A diagnosis' JSON record; its ``candidates`` (ranked, best first, each with ``kind``,
        ``location``, ``score`` and optional ``label``) are drawn.
    top : int
        Candidates shown in rank order (the best ``top``); below them, after a gap, the best
        candidate of each kind (``none`` too) that none of those is of, labelled "best <kind>:"
        ("nothing missing" for ``none``), so that the runner-up kinds the verdict's margin was
        set against are always seen.
    ax : matplotlib Axes, optional
        Draw into it instead of a new figure.

    Returns
    -------
    matplotlib.figure.Figure
        Bars coloured by kind (:data:`KIND_COLOURS`), a dot at each bar's end (the best's score
        is 0), best at the top; room on the right for the legend.
    """
    ranked = list(record.get("candidates") or [])
    entries = ranked[:top]
    shown, others = {e["kind"] for e in entries}, []
    for e in ranked[top:]:                          # the best of each kind not yet shown
        if e["kind"] not in shown:
            shown.add(e["kind"])
            others.append(e)
    labels = [candidate_label(e) for e in entries] + [
        candidate_label(e) if e["kind"] == "none" else f"best {e['kind']}: {candidate_label(e)}"
        for e in others]
    n_rows = len(entries) + len(others) + (1 if others else 0)
    width = 8.0 + 0.07 * max(0, max(map(len, labels), default=0) - 40)   # room for the labels
    fig = ax.figure if ax is not None else Figure(figsize=(width, 1.0 + 0.35 * max(n_rows, 2)))
    ax = ax if ax is not None else fig.add_subplot()
    if not entries:
        ax.text(0.5, 0.5, "no candidate screened", ha="center", va="center",
                transform=ax.transAxes)
        ax.set_axis_off()
        return fig
    rows = entries + others
    y = np.concatenate([np.arange(len(entries)), len(entries) + 1 + np.arange(len(others))])
    y = y.max() - y                                                    # best at the top
    scores = np.array([np.nan if e.get("score") is None else float(e["score"]) for e in rows])
    colours = [KIND_COLOURS.get(e["kind"], "k") for e in rows]
    ax.barh(y, scores, color=colours)
    ax.scatter(scores, y, color=colours, edgecolors="k", zorder=3)   # a zero score shows too
    if others:
        ax.axhline(y[len(entries)] + 1.0, color="0.5", linewidth=0.8, linestyle=":")
    high = np.nanmax(np.abs(scores)) if np.isfinite(scores).any() else 0.0
    ax.set_xlim(min(0.0, np.nanmin(scores)) if high else -1.0, 1.4 * high if high else 1.0)
    ax.set_yticks(y, labels, fontsize=8)
    ax.set_xlabel("score (BIC difference to the best candidate; lower is better)")
    ax.set_title(f"Candidate ranking (verdict: {record.get('verdict', '?')})")
    kinds = list(dict.fromkeys(e["kind"] for e in rows))
    ax.legend(handles=[Patch(color=KIND_COLOURS.get(k, "k"), label=k) for k in kinds],
              fontsize=8, loc="upper right")                # the best, shortest bars
    fig.tight_layout()
    return fig


def _value(gap: dict, key: str) -> float:
    value = (gap or {}).get(key)
    return np.nan if value is None or isinstance(value, dict) else float(value)


def plot_gap(record: dict, velocity: str = "model units") -> Figure:
    """The test-analysis gap before and after the named effects, as grouped bars per metric.

    Parameters
    ----------
    record : dict
        A diagnosis' JSON record: ``gap_before`` and ``gap_after`` with the frequency RMS errors
        (%), the largest cross-orthogonality off-diagonal, the smallest MAC, the mass-property
        errors ``mass`` (quantity -> %) and ``flutter_speed`` (model units, or null).
    velocity : str
        The flutter speed's unit (axis label).

    Returns
    -------
    matplotlib.figure.Figure
        One panel per group of :data:`GAP_PANELS` with a metric computed (test frequencies alone
        have no shape metrics), one for the mass errors when stated and one for the flutter
        speed when it was computed before and after.
    """
    before, after = record.get("gap_before") or {}, record.get("gap_after") or {}
    panels = [(title, unit, [(label, _value(before, k), _value(after, k)) for k, label in keys
                             if not np.isnan([_value(before, k), _value(after, k)]).all()])
              for title, unit, keys in GAP_PANELS]                  # a metric not computed: no bar
    panels = [panel for panel in panels if panel[2]]     # none of a panel's (no shapes): no panel
    mass = sorted(set(before.get("mass") or {}) | set(after.get("mass") or {}))
    if mass:
        panels.append(("mass properties", "error %", [
            (q, _value(before.get("mass"), q), _value(after.get("mass"), q)) for q in mass]))
    speeds = (_value(before, "flutter_speed"), _value(after, "flutter_speed"))
    if not np.isnan(speeds).all():
        panels.append(("flutter", f"speed [{velocity}]", [("lowest flutter speed", *speeds)]))
    widths = [max(2, len(rows)) for _, _, rows in panels]
    fig = Figure(figsize=(min(0.9 * sum(widths) + 2.0, 16.0), 3.6))
    axes = fig.subplots(1, len(panels), squeeze=False, width_ratios=widths)[0]
    width = 0.38
    for ax, (title, unit, rows) in zip(axes, panels):
        x = np.arange(len(rows))
        for side, (shift, color, label) in enumerate(((-width / 2, "0.6", "before"),
                                                      (width / 2, "tab:green", "after"))):
            values = [r[1 + side] for r in rows]
            bars = ax.bar(x + shift, values, width, color=color, label=label)
            ax.bar_label(bars, ["" if np.isnan(v) else f"{v:.3g}" for v in values], fontsize=7,
                         padding=1, rotation=90 if len(rows) > 3 else 0)  # 0 reads "0"
        finite = np.array([v for r in rows for v in r[1:] if not np.isnan(v)] or [0.0])
        low, high = min(finite.min(), 0.0), max(finite.max(), 0.0)
        pad = (0.25 if len(rows) > 3 else 0.12) * ((high - low) or 1.0)   # room for the values
        ax.set_ylim(low - pad if low < 0 else 0.0, high + pad)
        ax.set_xticks(x, [r[0] for r in rows], rotation=20, ha="right", fontsize=8)
        ax.axhline(0.0, color="k", linewidth=0.6)
        ax.set_title(title)
        ax.set_ylabel(unit)
    fig.legend(*axes[0].get_legend_handles_labels(), loc="upper left", ncols=2, fontsize=8,
               frameon=False)                          # above the panels, never on a bar
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 0.93))
    return fig
