"""Aerodynamic model plots: box layout and Delta Cp of a mode at one (M, k).

Compute functions (:func:`box_layout`, :func:`pressure_distribution`) return data; plot functions
(:func:`plot_box_layout`, :func:`plot_pressure`) draw it on a new matplotlib Figure (Agg canvas, no
pyplot state). Planforms are drawn in the x-y plane of the aerodynamic frame ACSID (x downstream).
Reduced frequency is Nastran's k = omega * b / V with b = REFC / 2.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure

from aero import dlm as _dlm
from aero.gaf import K_CONVENTION, modal_box_motion, pressure_coefficients
from structures.common.errors import InputError

PARTS = ("real", "imag", "abs", "phase")


@dataclass(frozen=True)
class BoxLayout:
    """Planform data in the ACSID x-y plane.

    ``panel_ids`` (np,), ``panel_outlines`` (np, 4, 2) corners P1, P2, P3, P4; ``box_ids`` (n,),
    ``box_corners`` (n, 4, 2), ``collocation`` (n, 2) 3/4-chord points, ``load_points`` (n, 2)
    1/4-chord points; ``grid_ids`` (ng,) and ``grid_xy`` (ng, 2) the spline grids (projected).
    """

    panel_ids: np.ndarray
    panel_outlines: np.ndarray
    box_ids: np.ndarray
    box_corners: np.ndarray
    collocation: np.ndarray
    load_points: np.ndarray
    grid_ids: np.ndarray
    grid_xy: np.ndarray


def box_layout(aero_model) -> BoxLayout:
    """Planform of panels, boxes, collocation/load points and spline grids (ACSID x-y plane).

    Parameters
    ----------
    aero_model : aero.model.AeroModel

    Returns
    -------
    BoxLayout
    """
    mesh = aero_model.mesh
    xhat = np.array([1.0, 0.0, 0.0])
    outlines = np.array([[p.p1, p.p1 + p.x12 * xhat, p.p4 + p.x43 * xhat, p.p4]
                         for p in aero_model.panels])[:, :, :2]
    grids = {int(g): x for s in aero_model.splines for g, x in zip(s.grid_ids, s.grid_xyz)}
    gids = np.array(sorted(grids), dtype=int)
    gxy = aero_model.aero_frame.from_basic(np.array([grids[g] for g in gids]).reshape(-1, 3))[:, :2]
    return BoxLayout(panel_ids=np.array([p.eid for p in aero_model.panels]),
                     panel_outlines=outlines, box_ids=np.asarray(mesh.box_id),
                     box_corners=np.asarray(mesh.corners)[:, :, :2],
                     collocation=np.asarray(mesh.collocation)[:, :2],
                     load_points=(0.5 * (mesh.doublet_in + mesh.doublet_out))[:, :2],
                     grid_ids=gids, grid_xy=gxy)


def _new_figure(size=(8.0, 6.0)) -> Figure:
    fig = Figure(figsize=size)
    FigureCanvasAgg(fig)
    return fig


def plot_box_layout(layout: BoxLayout, *, show_box_ids: bool = False,
                    show_load_points: bool = False) -> Figure:
    """Draw panel outlines, boxes, collocation points and spline grid points.

    Parameters
    ----------
    layout : BoxLayout
        From :func:`box_layout`.
    show_box_ids : bool
        Write each box id at its centre.
    show_load_points : bool
        Also mark the 1/4-chord load points.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = _new_figure()
    ax = fig.add_subplot(1, 1, 1)
    ax.add_collection(PolyCollection(layout.box_corners, facecolors="none", edgecolors="0.6",
                                     linewidths=0.5))
    for pid, outline in zip(layout.panel_ids, layout.panel_outlines):
        closed = np.vstack([outline, outline[:1]])
        ax.plot(closed[:, 0], closed[:, 1], "k-", lw=1.2)
        ax.annotate(f"CAERO1 {pid}", outline[0], fontsize=8, xytext=(3, 3),
                    textcoords="offset points")
    ax.plot(layout.collocation[:, 0], layout.collocation[:, 1], ".", color="tab:blue", ms=2,
            label="3/4-chord collocation points")
    if show_load_points:
        ax.plot(layout.load_points[:, 0], layout.load_points[:, 1], "+", color="tab:green", ms=3,
                label="1/4-chord load points")
    if layout.grid_ids.size:
        ax.plot(layout.grid_xy[:, 0], layout.grid_xy[:, 1], "o", color="tab:red", ms=5,
                mfc="none", label="spline grid points")
        for gid, (x, y) in zip(layout.grid_ids, layout.grid_xy):
            ax.annotate(str(gid), (x, y), fontsize=7, color="tab:red", xytext=(3, -8),
                        textcoords="offset points")
    if show_box_ids:
        centres = layout.box_corners.mean(axis=1)
        for bid, (x, y) in zip(layout.box_ids, centres):
            ax.text(x, y, str(bid), fontsize=5, ha="center", va="center")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("x (aerodynamic frame, downstream)")
    ax.set_ylabel("y (aerodynamic frame)")
    ax.set_title(f"{layout.box_ids.size} boxes on {layout.panel_ids.size} CAERO1 panels")
    ax.legend(loc="best", fontsize=8)
    return fig


def pressure_distribution(aero_model, modes_ds: xr.Dataset, mode: int, mach: float, k: float, *,
                          method: str = "quartic") -> xr.Dataset:
    """Delta Cp on every box for harmonic motion of one mode (unit modal amplitude).

    Parameters
    ----------
    aero_model : aero.model.AeroModel
    modes_ds : xarray.Dataset
        The modes contract.
    mode : int
        Mode number (the Dataset's ``mode`` coordinate).
    mach : float
        Mach number (< 1).
    k : float
        Reduced frequency k = omega * b / V, b = REFC / 2.
    method : {"quartic", "parabolic"}

    Returns
    -------
    xarray.Dataset
        ``delta_cp(box)`` complex (positive along the box normal), coordinates ``box_id(box)``,
        ``panel_id(box)``, ``x(box)``, ``y(box)`` (collocation point, ACSID frame).
    """
    modes = np.asarray(modes_ds["mode"].values)
    if mode not in modes:
        raise InputError(f"pressure_distribution: mode {mode} not in the modes Dataset "
                         f"({modes.tolist()}). Fix: pick one of those.")
    sel = int(np.flatnonzero(modes == mode)[0])
    h_c, s_c, _ = modal_box_motion(aero_model, modes_ds)
    D = _dlm.dlm_aic(aero_model.mesh, float(mach), [float(k)], refc=aero_model.refc, method=method,
                     symxz=aero_model.symxz)
    dcp = pressure_coefficients(D, h_c[:, sel:sel + 1], s_c[:, sel:sel + 1], np.array([k]),
                                aero_model.refc / 2.0)[0, :, 0]
    mesh = aero_model.mesh
    return xr.Dataset(
        {"delta_cp": ("box", dcp)},
        coords={"box_id": ("box", mesh.box_id), "panel_id": ("box", mesh.panel_id),
                "x": ("box", mesh.collocation[:, 0]), "y": ("box", mesh.collocation[:, 1])},
        attrs={"mode": int(mode), "mach": float(mach), "k": float(k), "k_convention": K_CONVENTION,
               "method": method, "units": "Delta Cp per unit modal coordinate (dimensionless / "
                                          "mode-shape unit)", "deck": aero_model.filename})


def plot_pressure(aero_model, cp_ds: xr.Dataset, *, part: str = "real") -> Figure:
    """Colour every box by a part of Delta Cp.

    Parameters
    ----------
    aero_model : aero.model.AeroModel
        Gives the box corners.
    cp_ds : xarray.Dataset
        From :func:`pressure_distribution`.
    part : {"real", "imag", "abs", "phase"}
        Phase in degrees.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if part not in PARTS:
        raise InputError(f"plot_pressure: unknown part {part!r}. Fix: use one of {PARTS}.")
    value = np.asarray(cp_ds["delta_cp"].values)
    shown = {"real": value.real, "imag": value.imag, "abs": np.abs(value),
             "phase": np.degrees(np.angle(value))}[part]
    mesh = aero_model.mesh
    if not np.array_equal(np.asarray(cp_ds["box_id"].values), mesh.box_id):
        raise InputError("plot_pressure: the Delta Cp Dataset was computed on another box mesh. "
                         "Fix: compute it with pressure_distribution on this aerodynamic model.")
    fig = _new_figure()
    ax = fig.add_subplot(1, 1, 1)
    coll = PolyCollection(mesh.corners[:, :, :2], array=shown, cmap="coolwarm" if part in
                          ("real", "imag") else "viridis", edgecolors="0.5", linewidths=0.2)
    if part in ("real", "imag"):
        vmax = max(float(np.abs(shown).max()), 1e-300)
        coll.set_clim(-vmax, vmax)
    ax.add_collection(coll)
    fig.colorbar(coll, ax=ax, label=f"{part}(Delta Cp)" + (" [deg]" if part == "phase" else ""))
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("x (aerodynamic frame, downstream)")
    ax.set_ylabel("y (aerodynamic frame)")
    ax.set_title(f"mode {cp_ds.attrs['mode']}, M = {cp_ds.attrs['mach']:g}, "
                 f"k = {cp_ds.attrs['k']:g} ({K_CONVENTION})")
    return fig
