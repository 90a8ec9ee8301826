"""Figures of the run's report: V-g / V-f of every stage overlaid (paper Figs. 11, 12, 17), the
flutter boundary of every stage against the envelope, and PNG data URIs to embed them.

Plotting only: the numbers come from the run folder (flutter.nc, summary.json). Figures are built on
:class:`matplotlib.figure.Figure` without pyplot, like :mod:`flutter.plots`.
"""
from __future__ import annotations

import base64
import io

from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from flutter.plots import plot_flutter_boundary
from flutter.summary import Envelope
from structures.units import MODEL_UNITS

#: Line style of stage k (cycled): the baseline solid, then dashed, dotted, dash-dotted.
STAGE_STYLES = ("-", "--", ":", "-.")


def png_data_uri(png: bytes) -> str:
    """``data:image/png;base64,...`` of PNG bytes (to embed a figure in a self-contained page)."""
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


def figure_data_uri(fig: Figure, dpi: int = 90) -> str:
    """A figure as a PNG data URI (no metadata, so the page names no web address)."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi, metadata={"Software": None})
    return png_data_uri(buffer.getvalue())


def vg_overlay(flutter: list, case: int, labels: list, *, title: str = "",
               g_limits=(-0.3, 0.2)) -> Figure:
    """V-g and V-f curves of one sweep at every stage, overlaid.

    The same root keeps its colour at every stage; the stage is told by the line style
    (:data:`STAGE_STYLES`: stage 0 solid). The legend names the rigid-body roots ("root 2 (short
    period)") when flutter.nc has ``root_label(root)``.

    Parameters
    ----------
    flutter : list of xarray.Dataset
        The flutter.nc of each stage (one configuration): ``damping``, ``frequency`` [Hz] and
        ``root_velocity`` on (case, velocity, root), ``velocity`` being the point index.
    case : int
        Index of the sweep on the ``case`` dim (the same sweep at every stage).
    labels : list of str
        Legend label of each stage, e.g. ``["stage 0 (baseline)", "stage 1"]``.
    g_limits : tuple
        Damping axis limits.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = Figure(figsize=(7.5, 7))
    ax_g, ax_f = fig.subplots(2, 1, sharex=True)
    roots = list(dict.fromkeys(int(r) for ds in flutter for r in ds["root"].values))
    units = MODEL_UNITS
    for k, (ds, label) in enumerate(zip(flutter, labels)):
        one = ds.sel(case=case)
        units = one["root_velocity"].attrs.get("units", units)
        style = STAGE_STYLES[k % len(STAGE_STYLES)]
        for r in one["root"].values:
            root = one.sel(root=r)
            color = f"C{roots.index(int(r)) % 10}"
            ax_g.plot(root["root_velocity"].values, root["damping"].values, style, color=color,
                      lw=1.2)
            ax_f.plot(root["root_velocity"].values, root["frequency"].values, style, color=color,
                      lw=1.2)
    ax_g.axhline(0.0, color="k", lw=0.8)
    ax_g.set_ylim(*g_limits)
    ax_g.set_ylabel("damping g [-]")
    ax_f.set_ylabel("frequency [Hz]")
    ax_f.set_xlabel(f"velocity [{units}]")
    names = {int(r): str(n) for ds in flutter if "root_label" in ds.coords
             for r, n in zip(ds["root"].values, ds["root_label"].values) if str(n)}
    root_keys = [Line2D([], [], color=f"C{i % 10}",
                        label=f"root {r}" + (f" ({names[r]})" if r in names else ""))
                 for i, r in enumerate(roots)]
    stage_keys = [Line2D([], [], color="k", ls=STAGE_STYLES[k % len(STAGE_STYLES)], label=label)
                  for k, label in enumerate(labels)]
    ax_g.legend(handles=root_keys, fontsize=7, ncol=3, loc="lower left")
    ax_f.legend(handles=stage_keys, fontsize=7, loc="upper left")
    ax_g.set_title(title or "V-g / V-f")
    fig.tight_layout()
    return fig


def boundary_figure(crossings: list, labels: list, envelope: Envelope | None = None, *,
                    units: str | None = None, title: str = "Flutter boundary") -> Figure:
    """Flutter and divergence speed versus Mach of every stage and configuration, against the
    envelope and 1.15 x envelope (:func:`flutter.plots.plot_flutter_boundary`).

    Parameters
    ----------
    crossings : list of dict[str, list of dict]
        ``crossings[k][configuration]``: the summary.json entries of stage ``k`` (``mach``,
        ``velocity``, ``kind``, ``root``).
    labels : list of str
        Label of each stage.
    envelope : Envelope, optional
    units : str, optional
        Velocity unit label of the speed axis (default: the envelope's, else "model units").

    Returns
    -------
    matplotlib.figure.Figure
    """
    points = [{**entry, "type": f"{label} {config} {entry['kind']}"}
              for stage, label in zip(crossings, labels)
              for config, entries in stage.items() for entry in entries]
    fig = plot_flutter_boundary(points, envelope, title=title)
    if units is not None:
        fig.axes[0].set_ylabel(f"speed [{units}]")
    return fig

