"""Plots: V-g / V-f curves (paper Figs. 11-12), flutter boundary vs envelope (Fig. 13) and a flutter
mode-shape snapshot (Fig. 14). Plotting only: the numbers come from flutter.pk / flutter.summary.
Figures are built on :class:`matplotlib.figure.Figure` without pyplot (no global figure state, no
display backend): save them with ``fig.savefig``; nothing needs closing.
"""
from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from flutter.results import is_flutter
from flutter.summary import MARGIN_FACTOR, Envelope
from structures.units import MODEL_UNITS


def plot_vg(ds: xr.Dataset, *, roots=None, title: str | None = None, g_limits=(-0.3, 0.2)):
    """V-g and V-f curves of a sweep, one line per tracked root, crossings marked; the legend names
    the rigid-body roots ("root 2 (short period)") when the sweep has ``root_label(root)``
    (:func:`flutter.rigid_roots.label_rigid_roots`).

    Parameters
    ----------
    ds : xarray.Dataset
        A :func:`flutter.pk.pk_solve` result (velocity or density sweep) or a
        :func:`flutter.kmethod.k_solve` result (each root drawn at its own V = omega b / k).
    roots : list of int, optional
        Roots to draw (default all).
    g_limits : tuple
        Damping axis limits.

    Returns
    -------
    matplotlib.figure.Figure
    """
    sweep = ds.attrs.get("sweep", "velocity")
    dim = "velocity" if sweep == "k" else sweep
    fig = Figure(figsize=(7, 7))
    ax_g, ax_f = fig.subplots(2, 1, sharex=True)
    names = (dict(zip(ds.root.values.tolist(), ds["root_label"].values.astype(str)))
             if "root_label" in ds.coords else {})
    for r in (ds.root.values if roots is None else roots):
        one = ds.sel(root=r)
        x = np.broadcast_to(one[dim].values, one.damping.shape)
        name = names.get(int(r), "")
        line, = ax_g.plot(x, one.damping.values,
                          label=f"root {int(r)}" + (f" ({name})" if name else ""))
        ax_f.plot(x, one.frequency.values, color=line.get_color())
        bad = ~one.converged.values
        if bad.any():
            ax_g.plot(x[bad], one.damping.values[bad], "x", color=line.get_color())
    for i in range(ds.sizes.get("crossing", 0)):
        xc = float(ds[f"crossing_{dim}"][i])
        ax_g.plot(xc, 0.0, "ko", mfc="none")
        ax_f.plot(xc, float(ds.crossing_frequency[i]), "ko", mfc="none")
    ax_g.axhline(0.0, color="k", lw=0.8)
    ax_g.set_ylim(*g_limits)
    ax_g.set_ylabel("damping g" + (" (required, k method)" if sweep == "k" else ""))
    ax_f.set_ylabel("frequency [Hz]")
    ax_f.set_xlabel(f"{dim} [{ds[dim].attrs.get('units', MODEL_UNITS)}]")
    ax_g.legend(fontsize=7, ncol=3)
    ax_g.set_title(title or f"{ds.attrs.get('method', 'PK')} V-g / V-f")
    fig.tight_layout()
    return fig


def plot_flutter_boundary(points: list[dict], envelope: Envelope | None = None, *,
                          title: str = "Flutter boundary"):
    """Flutter (and divergence) speed versus Mach against the envelope and 1.15 x envelope.

    Parameters
    ----------
    points : list of dict
        Entries of :func:`flutter.summary.flutter_summary` (or summary.json) with ``mach``,
        ``velocity``, ``kind`` and optional ``type``.
    envelope : Envelope, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = Figure(figsize=(7, 5))
    ax = fig.add_subplot()
    groups: dict = {}
    for p in points:
        groups.setdefault((p["kind"], p.get("type", p["kind"]), p.get("root")), []).append(p)
    for (kind, typ, root), pts in sorted(groups.items(), key=lambda kv: str(kv[0])):
        pts = sorted(pts, key=lambda p: p["mach"])
        ax.plot([p["mach"] for p in pts], [p["velocity"] for p in pts],
                "s--" if is_flutter(kind) else "d:", label=f"{typ} (root {root})")
    if envelope is not None:
        m = np.asarray(envelope.mach)
        ax.plot(m, envelope.velocity, "k-", label="envelope")
        ax.plot(m, MARGIN_FACTOR * np.asarray(envelope.velocity), "k--",
                label=f"{MARGIN_FACTOR:.2f} x envelope")
    ax.set_xlabel("Mach")
    ax.set_ylabel(f"speed [{envelope.units if envelope else MODEL_UNITS}]")
    ax.set_title(title)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def plot_mode_snapshot(modes: xr.Dataset, eigenvector: np.ndarray, *, component: int = 3,
                       phases=(0.0, 0.25, 0.5), scale: float | None = None, title: str = ""):
    """Snapshot of a flutter mode: component ``component`` of sum_j Re(u_j e^{i 2 pi phase}) phi_j
    at each grid, drawn over the grid plan form for several phases of the cycle.

    Parameters
    ----------
    modes : xarray.Dataset
        Modes contract (shape(mode, dof), grid/component/x/y coordinates).
    eigenvector : ndarray, shape (nmode,) complex
        Flutter eigenvector in modal coordinates (same modes).
    component : int
        1..6 (3 = vertical translation).

    Returns
    -------
    matplotlib.figure.Figure
    """
    sel = modes["component"].values == component
    shape = np.asarray(modes["shape"].values)[:, sel]
    x, y = modes["x"].values[sel], modes["y"].values[sel]
    disp = np.asarray(eigenvector) @ shape  # complex motion of each grid
    amp = np.abs(disp).max() or 1.0
    scale = scale if scale is not None else 0.15 * max(np.ptp(x), np.ptp(y), 1e-12) / amp
    fig = Figure(figsize=(4 * len(phases), 4))
    axes = fig.subplots(1, len(phases), squeeze=False, subplot_kw={"projection": "3d"})
    for ax, ph in zip(axes[0], phases):
        z = scale * np.real(disp * np.exp(2j * np.pi * ph))
        ax.scatter(x, y, z, c=z, cmap="coolwarm", s=8)
        ax.set_title(f"{title} phase {ph:.2f}")
        ax.set_xlabel("x")
        ax.set_ylabel("y")
    fig.tight_layout()
    return fig
