"""Figures of the mode selection (plotting only; the numbers come from pipeline.selection).

- :func:`plot_selection_study`: flexible modes needed versus threshold, one line per critical root
  (configuration x Mach x flutter mode) and a black dashed line per configuration for the joint
  selection;
- :func:`plot_participation`: the participation of every critical root as bars over the modes,
  coloured by the role the selection gave each mode (the paper's Table 6 as a picture).
"""
from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure  # no pyplot: no global figure state, no display backend
from matplotlib.patches import Patch
from matplotlib.ticker import MaxNLocator

from pipeline.selection import point_labels

ROLE_COLOURS = {"rigid": "0.45", "primary": "tab:red", "secondary": "tab:orange", "": "tab:blue"}
JOINT_STYLES = ("--", "-.", ":")  # the joint selection of each configuration, in black
ROLE_NAMES = {"rigid": "rigid-body", "primary": "primary", "secondary": "secondary", "": "not selected"}


def plot_selection_study(study: xr.Dataset, *, ax=None) -> Figure:
    """Modes needed (with the rigid-body modes) versus the participation threshold.

    Parameters
    ----------
    study : xarray.Dataset
        From :func:`pipeline.selection.selection_study`: ``n_modes(threshold, flutter_point)`` and
        ``n_primary(threshold, configuration)``.
    ax : matplotlib Axes, optional
        Draw into it instead of a new figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = ax.figure if ax is not None else Figure(figsize=(7.0, 4.5))
    ax = ax if ax is not None else fig.add_subplot()
    pct = 100.0 * study["threshold"].values
    for i, label in enumerate(point_labels(study)):
        ax.plot(pct, study["n_modes"].values[:, i], marker="o", label=label)
    for c, name in enumerate(study["configuration"].values):
        if int(study["critical_roots"].values[c]):
            ax.plot(pct, study["n_primary"].values[:, c], color="k", marker="s",
                    linestyle=JOINT_STYLES[c % len(JOINT_STYLES)], label=f"{name}: all critical roots")
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("participation threshold, with the rigid-body modes [%]")
    ax.set_ylabel("flexible modes needed")
    ax.set_title(f"mode-selection study (first {study.attrs['flutter_modes']} flutter modes)")
    ax.grid(True, alpha=0.3)
    if study.sizes["flutter_point"]:
        ax.legend(fontsize=7)
    else:
        ax.text(0.5, 0.5, "no critical flutter roots", transform=ax.transAxes, ha="center")
    fig.tight_layout()
    return fig


def plot_participation(selection: xr.Dataset) -> Figure:
    """Participation [%] of every mode in each critical root, bars coloured by role.

    Parameters
    ----------
    selection : xarray.Dataset
        From :func:`pipeline.selection.select_modes`.

    Returns
    -------
    matplotlib.figure.Figure
        One panel per critical root (up to three per row), modes on the horizontal axis; the
        panel title gives the root and its primary / secondary totals.
    """
    pts = np.flatnonzero(selection["critical"].values)
    ncol = max(1, min(3, pts.size))
    nrow = max(1, -(-pts.size // ncol))
    fig = Figure(figsize=(4.2 * ncol, 3.0 * nrow + 0.6))
    if pts.size == 0:
        ax = fig.add_subplot()
        ax.text(0.5, 0.5, "no critical flutter roots", transform=ax.transAxes, ha="center")
        ax.set_axis_off()
        return fig
    labels = point_labels(selection)
    modes = selection["mode"].values
    for n, p in enumerate(pts):
        ax = fig.add_subplot(nrow, ncol, n + 1)
        name = str(selection["point_configuration"].values[p])
        role = selection["role"].sel(configuration=name).values
        share = selection["participation"].values[p]
        have = np.isfinite(share)
        pos = np.arange(have.sum())
        ax.bar(pos, share[have], color=[ROLE_COLOURS[r] for r in role[have]])
        ax.set_xticks(pos, labels=[str(int(m)) for m in modes[have]], rotation=90, fontsize=7)
        ax.set_title(f"{labels[p]}\nrigid+primary {float(selection['primary_total'][p]):.1f} %, "
                     f"+secondary {float(selection['secondary_total'][p]):.1f} %", fontsize=8)
        ax.set_xlabel("mode")
        ax.set_ylabel("participation [%]")
    fig.legend(handles=[Patch(color=c, label=ROLE_NAMES[r]) for r, c in ROLE_COLOURS.items()],
               loc="lower center", ncol=4, fontsize=8)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    return fig
