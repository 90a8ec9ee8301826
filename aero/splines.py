"""Splines from structural grid displacements to aerodynamic box motion (Nastran's G_kg).

Two interpolants, both from Harder & Desmarais, "Interpolation using surface splines", J. Aircraft
9(2), 1972, as used by Nastran (MSC Nastran Aeroelastic Analysis User's Guide, section 2.3
"Interconnection of the structure with aerodynamics"):

* SPLINE1, **infinite-plate spline** (IPS). In the plane of the CAERO1 panel the out-of-plane
  displacement is that of an infinite plate (bending stiffness D = 1) loaded by point forces F_i at
  the projections (x_i, y_i) of the structural grids::

      w(x, y) = a0 + a1 x + a2 y + sum_i F_i K(r_i),  K(r) = r^2 ln(r^2) / (16 pi)     (H&D eq. 8)

  with sum F_i = sum F_i x_i = sum F_i y_i = 0 (equilibrium) and w(x_i, y_i) + DZ F_i = w_i (an
  attachment spring of flexibility DZ, in units of area, smooths the fit; DZ = 0 interpolates).
  Only the out-of-plane translation of each grid enters.

* SPLINE2, **beam spline** (Nastran's "linear spline"). A free-free beam (EI = 1) with torsion
  (GJ = 1/DTOR) along the spline axis: the y axis of the spline's CID projected on the panel plane.
  Bending deflection Z(y) and twist theta(y) come from point forces P_i, moments M_i and torques
  T_i at the grids' axial stations y_i::

      Z(y)     = a0 + a1 y + sum_i P_i G(y - y_i) - sum_i M_i G'(y - y_i),  G(r) = |r|^3 / 12
      theta(y) = b0 + sum_i T_i H(y - y_i),                                 H(r) = -DTOR |r| / 2

  (the infinite-beam Green's functions of EI Z'''' = p and GJ theta'' = -t). What is taken from
  the Nastran Aeroelastic Analysis User's Guide (sec. 2.3, "linear splines") and the Quick
  Reference Guide (SPLINE2): the spline is a beam along the projection of the CID y axis on the
  panel plane, with bending and torsion, the torsion flexibility ratio DTOR = EI/GJ, the grids'
  out-of-plane translation attached with flexibility DZ, their rotation about the spline x axis
  (bending slope Z') with DTHX and about its y axis (twist theta) with DTHY, a negative DTHX/DTHY
  meaning "not attached". Our choices: EI = 1 in the model's units (so DZ is in length^3 and DTHX,
  DTHY in length; DZ = DTHX = DTHY = 0, the usual case, is independent of that choice); a blank
  DTHX/DTHY reads as 0.0 (pyNastran's default: attached); with no twist attached the twist is
  zero. A chordwise-rigid section gives the displacement at chordwise offset x (along the spline x
  axis) as ``h = Z(y) - x theta(y)`` and ``dh/dx = -theta(y)``; outside the grids' span the beam
  continues straight (linear Z, constant theta).

With zero attachment flexibilities both interpolate the grid values exactly; both reproduce rigid
motion exactly (the polynomial terms). The transformation outputs, for every box, the normal
displacement h and slope dh/dx (x = free-stream direction) at the 3/4-chord collocation point (for
the downwash) and h at the 1/4-chord load point (for the forces), per structural degree of freedom
(grid, component 1..6) in the basic frame.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from structures.common.errors import InputError, card_message

_REL_RANK_TOL = 1e-9


def _solve_bordered(C: np.ndarray, B: np.ndarray, label: str) -> np.ndarray:
    """Inverse of the bordered system [[C, B], [B^T, 0]] restricted to its first block column.

    Returns X (nrow + npoly, nrow) with [coeffs; poly] = X @ rhs.
    """
    n, p = B.shape
    scale = np.linalg.norm(B, axis=0)
    if np.any(scale == 0) or np.linalg.matrix_rank(B / scale, tol=_REL_RANK_TOL * max(n, 1)) < p:
        raise InputError(f"{label}: the structural points cannot define the spline's rigid motion "
                         "(too few points in reach, or all on one line / one station).")
    A = np.zeros((n + p, n + p))
    A[:n, :n] = C
    A[:n, n:] = B
    A[n:, :n] = B.T
    rhs = np.zeros((n + p, n))
    rhs[:n] = np.eye(n)
    try:
        return np.linalg.solve(A, rhs)
    except np.linalg.LinAlgError as exc:
        raise InputError(f"{label}: singular spline system ({exc}); coincident structural "
                         "points?") from exc


def ips_weights(grid_xy: np.ndarray, points_xy: np.ndarray, dz: float = 0.0,
                label: str = "SPLINE1") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Infinite-plate spline weights (Harder & Desmarais 1972).

    Parameters
    ----------
    grid_xy : ndarray, shape (n, 2)
        In-plane coordinates of the structural points (projections on the spline plane).
    points_xy : ndarray, shape (m, 2)
        In-plane coordinates where the displacement is wanted.
    dz : float
        Attachment flexibility (area units; 0 interpolates exactly).
    label : str
        Names the spline in error messages.

    Returns
    -------
    W, Wx, Wy : ndarray, shape (m, n)
        w(points) = W @ w_grid, dw/dx = Wx @ w_grid, dw/dy = Wy @ w_grid.
    """
    g = np.asarray(grid_xy, dtype=float).reshape(-1, 2)
    p = np.asarray(points_xy, dtype=float).reshape(-1, 2)
    n = g.shape[0]
    if n < 3:
        raise InputError(f"{label}: {n} structural point(s) in reach; the infinite-plate spline "
                         "needs at least 3 not on one line.")
    length = max(np.ptp(g, axis=0).max(), 1e-300)  # scale for conditioning; K is rescaled below

    def kernel(d):  # K(r) = r^2 ln r^2 / (16 pi), H&D eq. 8 with D = 1
        r2 = np.sum(d * d, axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            lg = np.where(r2 > 0, np.log(r2), 0.0)
        return r2 * lg / (16.0 * np.pi), lg

    dgg = g[:, None, :] - g[None, :, :]
    K, _ = kernel(dgg)
    C = K + dz * np.eye(n)
    B = np.column_stack([np.ones(n), g / length])
    X = _solve_bordered(C, B, label)  # (n+3, n)
    dpg = p[:, None, :] - g[None, :, :]
    Kp, lg = kernel(dpg)
    dK = 2.0 * dpg * (lg[..., None] + 1.0) / (16.0 * np.pi)  # d/dx, d/dy of r^2 ln r^2 / (16 pi)
    dK = np.where((np.sum(dpg * dpg, axis=-1) > 0)[..., None], dK, 0.0)
    F, a = X[:n], X[n:]
    W = Kp @ F + np.column_stack([np.ones(len(p)), p / length]) @ a
    Wx = dK[..., 0] @ F + np.outer(np.ones(len(p)), a[1] / length)
    Wy = dK[..., 1] @ F + np.outer(np.ones(len(p)), a[2] / length)
    return W, Wx, Wy


def beam_weights(grid_y: np.ndarray, points_xy: np.ndarray, *, dz: float = 0.0, dtor: float = 1.0,
                 dthx: float = 0.0, dthy: float = 0.0,
                 label: str = "SPLINE2") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Beam-spline weights (bending + torsion along the spline y axis; see module docstring).

    Parameters
    ----------
    grid_y : ndarray, shape (n,)
        Axial stations of the structural points along the spline axis.
    points_xy : ndarray, shape (m, 2)
        Spline-frame (x, y) of the wanted points: x chordwise offset from the axis, y axial station.
    dz, dtor, dthx, dthy : float
        SPLINE2 flexibilities: translation (length^3 with EI = 1), EI/GJ, rotation about the
        spline x axis (slope) and about its y axis (twist); negative dthx/dthy = not attached.
    label : str
        Names the spline in error messages.

    Returns
    -------
    W, Wx, Wy : ndarray, shape (m, n, 3)
        Weights of the grid inputs (out-of-plane translation, rotation about spline x, rotation
        about spline y) for h, dh/dx and dh/dy at the points.
    """
    y = np.asarray(grid_y, dtype=float).reshape(-1)
    p = np.asarray(points_xy, dtype=float).reshape(-1, 2)
    n, m = y.size, p.shape[0]
    slope, twist = dthx >= 0, dthy >= 0

    def G0(r):  # infinite-beam deflection under a unit load, EI = 1 (EI d4Z/dy4 = delta)
        return np.abs(r) ** 3 / 12.0

    def G1(r):
        return r * np.abs(r) / 4.0

    def G2(r):
        return np.abs(r) / 2.0

    dyy = y[:, None] - y[None, :]
    if slope:  # rows: Z_i, Z'_i; unknowns P_j, M_j; polynomial a0 + a1 y  (H&D bordered system)
        C = np.block([[G0(dyy), -G1(dyy)], [G1(dyy), -G2(dyy)]])
        C += np.diag(np.r_[np.full(n, dz), np.full(n, dthx)])
        B = np.block([[np.ones((n, 1)), y[:, None]], [np.zeros((n, 1)), np.ones((n, 1))]])
    else:
        C = G0(dyy) + dz * np.eye(n)
        B = np.column_stack([np.ones(n), y])
    Xb = _solve_bordered(C, B, label + " (bending)")
    nb = C.shape[0]
    dpy = p[:, 1][:, None] - y[None, :]
    # Z(y), Z'(y) at the points as linear maps of the bending unknowns [P, (M), a0, a1]
    Zrow = [G0(dpy)] + ([-G1(dpy)] if slope else []) + [np.ones((m, 1)), p[:, 1:2]]
    Zprow = [G1(dpy)] + ([-G2(dpy)] if slope else []) + [np.zeros((m, 1)), np.ones((m, 1))]
    Z = np.hstack(Zrow) @ Xb  # (m, nb): weights of [w_i, (thx_i)]
    Zp = np.hstack(Zprow) @ Xb
    W = np.zeros((m, n, 3))
    Wx = np.zeros((m, n, 3))
    Wy = np.zeros((m, n, 3))
    W[:, :, 0] = Z[:, :n]
    Wy[:, :, 0] = Zp[:, :n]
    if slope:
        W[:, :, 1] = Z[:, n:nb]
        Wy[:, :, 1] = Zp[:, n:nb]
    if twist:  # theta(y) = b0 + sum T_j H(y - y_j), H = -DTOR |r| / 2
        Ct = -dtor * np.abs(dyy) / 2.0 + dthy * np.eye(n)
        Xt = _solve_bordered(Ct, np.ones((n, 1)), label + " (torsion)")
        th = np.hstack([-dtor * np.abs(dpy) / 2.0, np.ones((m, 1))]) @ Xt  # (m, n)
        thp = (-dtor * np.sign(dpy) / 2.0) @ Xt[:n]
        x = p[:, 0][:, None]
        W[:, :, 2] = -x * th  # h = Z - x theta
        Wx[:, :, 2] = -th  # dh/dx = -theta
        Wy[:, :, 2] = -x * thp  # dh/dy = Z' - x theta'
    return W, Wx, Wy


@dataclass(frozen=True)
class SplineMatrices:
    """G_kg: box motion per structural degree of freedom.

    ``grid`` (ndof,), ``component`` (ndof,) label the columns (basic-frame components 1..6);
    ``box_ids`` (nbox,) the rows, in mesh order. ``h_colloc`` and ``slope_colloc`` (nbox, ndof)
    give the normal displacement and its derivative along the free stream at the 3/4-chord
    collocation points, ``h_load`` (nbox, ndof) the normal displacement at the 1/4-chord load
    points.
    """

    box_ids: np.ndarray
    grid: np.ndarray
    component: np.ndarray
    h_colloc: np.ndarray
    slope_colloc: np.ndarray
    h_load: np.ndarray


def spline_frame(spline, normal: np.ndarray, p1: np.ndarray,
                 aero_frame) -> tuple[np.ndarray, np.ndarray]:
    """Origin (3,) and axes (3, 3) (rows x, y, z) of a spline's plane frame, in the ACSID frame.

    Parameters
    ----------
    spline : aero.model.Spline
    normal : ndarray, shape (3,)
        Unit normal of the spline's CAERO1 panel (ACSID frame): the spline z axis.
    p1 : ndarray, shape (3,)
        The panel's leading-edge root corner (ACSID frame): a point of the plane, the IPS origin.
    aero_frame : aero.model.Frame
        The ACSID frame.
    """
    n = np.asarray(normal, dtype=float) / np.linalg.norm(normal)
    p1 = np.asarray(p1, dtype=float)
    if spline.kind == "IPS":
        ex = np.array([1.0, 0.0, 0.0]) - n[0] * n  # free stream projected on the plane
        if np.linalg.norm(ex) < 1e-9:
            raise InputError(card_message("the panel is normal to the free stream.",
                                          card=spline.card, card_id=spline.eid,
                                          filename=spline.filename,
                                          fix="check the CAERO1 geometry."))
        ex /= np.linalg.norm(ex)
        return p1, np.vstack([ex, np.cross(n, ex), n])
    cid_y = aero_frame.axes @ spline.frame.axes[1]  # CID y axis in ACSID components
    ey = cid_y - (cid_y @ n) * n  # projected on the panel plane (QRG SPLINE2 remarks)
    if np.linalg.norm(ey) < 1e-9:
        raise InputError(card_message(f"the y axis of CID {spline.frame.cid} is normal to the "
                                      "panel.", card=spline.card, card_id=spline.eid,
                                      filename=spline.filename,
                                      fix="choose a CID whose y axis lies along the elastic axis."))
    ey /= np.linalg.norm(ey)
    origin = aero_frame.from_basic(spline.frame.origin)
    origin = origin - ((origin - p1) @ n) * n  # axis projected on the panel plane
    return origin, np.vstack([np.cross(ey, n), ey, n])


def spline_transform(spline, *, grid_aero: np.ndarray, colloc: np.ndarray, load: np.ndarray,
                     frame_origin: np.ndarray, frame_axes: np.ndarray,
                     aero_axes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """G_kg of one spline for its boxes.

    Parameters
    ----------
    spline : aero.model.Spline
    grid_aero : ndarray, shape (ng, 3)
        Spline grid positions in the ACSID frame.
    colloc, load : ndarray, shape (nb, 3)
        Collocation (3/4 chord) and load (1/4 chord) points of the spline's boxes, ACSID frame.
    frame_origin : ndarray (3,), frame_axes : ndarray (3, 3)
        The spline plane frame (ACSID frame; rows x, y, z with z the box normal).
    aero_axes : ndarray, shape (3, 3)
        Rows: ACSID unit axes in basic.

    Returns
    -------
    h_colloc, slope_colloc, h_load : ndarray, shape (nb, 6 * ng)
        Columns ordered grid-major, components 1..6 (basic frame).
    """
    label = card_message("", card=spline.card, card_id=spline.eid,
                         filename=spline.filename).rstrip(": ")

    def local(points):
        return (np.asarray(points, dtype=float) - frame_origin) @ frame_axes.T

    g = local(grid_aero)
    pts = np.vstack([local(colloc), local(load)])
    nb = len(colloc)
    if spline.kind == "IPS":
        W, Wx, Wy = (w[..., None] * np.array([1.0, 0.0, 0.0])
                     for w in ips_weights(g[:, :2], pts[:, :2], spline.dz, label))
    else:
        W, Wx, Wy = beam_weights(g[:, 1], pts[:, :2], dz=spline.dz, dtor=spline.dtor,
                                 dthx=spline.dthx, dthy=spline.dthy, label=label)
    # spline-frame inputs (w, rot_x, rot_y) from basic components: rows of the frame axes in basic
    axes_basic = frame_axes @ aero_axes  # (3, 3): spline x, y, z in basic
    ng = g.shape[0]

    def to_dofs(Wk):  # (m, ng, 3) -> (m, 6 ng)
        out = np.zeros((Wk.shape[0], ng, 6))
        out[:, :, 0:3] = Wk[:, :, 0:1] * axes_basic[2]  # w = e_z . u
        out[:, :, 3:6] = Wk[:, :, 1:2] * axes_basic[0] + Wk[:, :, 2:3] * axes_basic[1]
        return out.reshape(Wk.shape[0], 6 * ng)

    flow = frame_axes[:, 0]  # free stream (ACSID x) in spline-frame components
    h = to_dofs(W)
    slope = to_dofs(Wx * flow[0] + Wy * flow[1])  # dh/dx_aero = grad h . x_aero
    return h[:nb], slope[:nb], h[nb:]
