"""Longitudinal stability derivatives of an aerodynamic model from the VLM and the DLM at k -> 0.

The derivatives of the rigid aircraft's lift and pitching moment with respect to the angle of
attack alpha, the pitch rate q and the rate of change of alpha (Etkin & Reid, *Dynamics of Flight:
Stability and Control*, 3rd ed., 1996, ch. 5, stability derivatives, the alpha-dot derivatives as
the lag of the downwash; Bisplinghoff, Ashley & Halfman, *Aeroelasticity*, 1955,
ch. 5 for the quasi-steady expansion of the unsteady forces)::

    C_L = C_L_alpha alpha + C_L_q q_hat + C_L_alphadot alphadot_hat
    C_m = C_m_alpha alpha + C_m_q q_hat + C_m_alphadot alphadot_hat
    q_hat = q c / (2 V),  alphadot_hat = alphadot c / (2 V)

with L = q_dyn S C_L and M = q_dyn S c C_m about the reference point (normally the CG), c = REFC.

Sign convention (stated once). Everything is in the aerodynamic frame ACSID (free stream along
+x, :mod:`aero.model`): lift is the force along +z of that frame, the pitching moment M is the
moment about +y through the reference point, and alpha, theta and q are rotations about +y, which
move points ahead of the reference point (smaller x) towards +z ("nose up" when +z is up). A
rigid pitch theta displaces a point by dz = -theta (x - x_ref); a pitch rate q moves it with
w = -q (x - x_ref). Because c / (2 V) = b / V with b = REFC / 2, unit q_hat at reduced frequency
k is the pitch rate of a harmonic pitch i k theta (Nastran's k = omega b / V).

How each derivative is computed (the boxes' motion is rigid, no splines involved):

* C_L_alpha, C_m_alpha: the steady vortex lattice (:func:`aero.vlm.steady_aic`) with the
  normalwash of a unit rotation, w / V = -n_z (flow tangency w/V = dh/dx, :mod:`aero.gaf`).
* C_L_q, C_m_q: the steady vortex lattice with the normalwash of a steady pitch rate at alpha = 0,
  w / V = -n_z (x - x_ref) / b per unit q_hat (the i k h / b part of the harmonic pitch).
* C_L_alphadot, C_m_alphadot: what is left of the k-derivative of the harmonic pitch forces
  Q_pitch(ik) = Q0 + i k Q1 + O(k^2 ln k) once the quasi-steady pitch-rate part is taken out:
  Q1 = C_q + C_alphadot, and C_alphadot = Im F(D(k)^-1 w_alpha) / k, the out-of-phase response of
  the doublet lattice (:func:`aero.dlm.dlm_aic`) to a harmonic alpha without pitch-rate normalwash
  (the lag of the wake, and of the downwash at a tail), at a small k (default 1e-4).

:func:`flexible_derivatives` adds the elastic modes in quasi-static equilibrium (derivatives of the
elastic aircraft at a dynamic pressure). Forces are those of the modelled boxes: with AERO
SYMXZ = +1 (half model) they are the half aircraft's, and S defaults to the half's planform area,
to go with the half model's mass.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from aero.dlm import dlm_aic
from aero.gaf import modal_box_motion
from aero.vlm import check_mach, steady_aic
from structures.common.errors import InputError, card_message

__all__ = ["StabilityDerivatives", "flexible_derivatives", "longitudinal_inertia",
           "quasi_steady_forces", "rigid_box_motion", "stability_derivatives"]

DERIVATIVES = ("cl_alpha", "cm_alpha", "cl_q", "cm_q", "cl_alphadot", "cm_alphadot")
#: Reduced frequency at which the alpha-dot derivatives are taken (k = omega b / V): the remainder
#: of the low-k expansion is O(k ln k); at 1e-4 the derivatives agree with k = 1e-3 within 1.5 %.
K_ALPHADOT = 1e-4


@dataclass(frozen=True)
class StabilityDerivatives:
    """Longitudinal stability derivatives of a rigid aircraft (module docstring for conventions).

    Attributes
    ----------
    cl_alpha, cm_alpha : float
        Per radian.
    cl_q, cm_q, cl_alphadot, cm_alphadot : float
        Per unit q c / (2 V) and alphadot c / (2 V).
    reference_area : float
        S (model length units squared).
    reference_chord : float
        c = AERO/AEROS REFC (model length unit).
    reference_point : (3,) float
        Moment reference point, basic frame.
    mach : float
    symxz : int
        AERO SYMXZ of the model: +1 means forces (and S) of the modelled half.
    k_alphadot : float
        Reduced frequency k = omega b / V, b = c / 2, of the alpha-dot derivatives.
    dynamic_pressure : float
        0 for the rigid aircraft; the dynamic pressure of :func:`flexible_derivatives`.
    """

    cl_alpha: float
    cm_alpha: float
    cl_q: float
    cm_q: float
    cl_alphadot: float
    cm_alphadot: float
    reference_area: float
    reference_chord: float
    reference_point: np.ndarray
    mach: float
    symxz: int = 0
    k_alphadot: float = K_ALPHADOT
    dynamic_pressure: float = 0.0

    def __post_init__(self):
        values = [getattr(self, n) for n in DERIVATIVES]
        point = np.array(self.reference_point, dtype=float).reshape(-1)
        if not np.all(np.isfinite(values)) or point.shape != (3,) or \
                not np.all(np.isfinite(point)):
            raise InputError(card_message(
                f"stability derivatives {dict(zip(DERIVATIVES, values))} or reference point "
                f"{point.tolist()} are not finite.", fix="give finite derivatives and a (3,) "
                "reference point."))
        if not (0 < self.reference_area < np.inf and 0 < self.reference_chord < np.inf):
            raise InputError(card_message(
                f"reference area {self.reference_area} and chord {self.reference_chord} must be "
                "positive.", card="AEROS/AERO", fix="give REFC (and S) > 0."))
        point.setflags(write=False)
        object.__setattr__(self, "reference_point", point)

    @property
    def units(self) -> dict:
        """Units of the fields, by name."""
        return {"cl_alpha": "1/rad", "cm_alpha": "1/rad", "cl_q": "1 per q c/(2V)",
                "cm_q": "1 per q c/(2V)", "cl_alphadot": "1 per alphadot c/(2V)",
                "cm_alphadot": "1 per alphadot c/(2V)", "reference_area": "length^2",
                "reference_chord": "length", "reference_point": "length (basic frame)"}


def rigid_box_motion(mesh, reference_point) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Normal displacement and slope of the boxes in rigid plunge and pitch.

    Plunge: unit displacement along +z of the mesh frame. Pitch: unit rotation about +y through
    ``reference_point`` (displacement (dz, 0, -dx), module docstring), so the normal displacement
    is h = n . (dz, 0, -dx) and its slope dh/dx = -n_z.

    Parameters
    ----------
    mesh : aero.panels.BoxMesh
        n boxes in the aerodynamic frame.
    reference_point : (3,) float
        Pitch axis point, aerodynamic frame.

    Returns
    -------
    h_colloc, slope_colloc, h_load : ndarray, shape (n, 2)
        Columns plunge, pitch; as :func:`aero.gaf.modal_box_motion`.
    """
    ref = np.asarray(reference_point, dtype=float)
    normal = np.asarray(mesh.normal)
    load = 0.5 * (np.asarray(mesh.doublet_in) + np.asarray(mesh.doublet_out))

    def normal_displacement(points):
        d = points - ref
        return np.column_stack([normal[:, 2], normal[:, 0] * d[:, 2] - normal[:, 2] * d[:, 0]])

    slope = np.column_stack([np.zeros(mesh.n), -normal[:, 2]])
    return normal_displacement(np.asarray(mesh.collocation)), slope, normal_displacement(load)


def quasi_steady_forces(aero_model, mach: float, h_colloc: np.ndarray, slope: np.ndarray,
                        h_load: np.ndarray, *, k: float = K_ALPHADOT,
                        method: str = "quartic") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Low-k expansion Q(ik) = Q0 + i k (Q1_rate + Q1_lag) + O(k^2 ln k) of box-motion forces.

    Q is the generalized force of :mod:`aero.gaf` (G_kg^T S_kj Delta Cp per unit dynamic pressure),
    with the normalwash w/V = dh/dx + i (k/b) h split into its two parts: Q0 and Q1_lag from the
    slope (steady vortex lattice; out-of-phase doublet-lattice response at a small k, divided by
    k), Q1_rate from the displacement rate h / b (steady vortex lattice).

    Parameters
    ----------
    aero_model : aero.model.AeroModel
    mach : float
    h_colloc, slope, h_load : ndarray, shape (nbox, n)
        Box motions (:func:`rigid_box_motion`, :func:`aero.gaf.modal_box_motion`).
    k : float
        Small reduced frequency k = omega b / V, b = REFC / 2, of Q1_lag.
    method : {"quartic", "parabolic"}

    Returns
    -------
    q0, q1_rate, q1_lag : ndarray, shape (n, n)
        Force on motion i per unit motion j.
    """
    mach = check_mach(mach)
    if not 0.0 < k <= 0.01:
        raise InputError(card_message(f"k_alphadot={k} is not a small positive reduced "
                                      "frequency.", fix="use 0 < k_alphadot <= 0.01 (default "
                                                        f"{K_ALPHADOT})."))
    mesh = aero_model.mesh
    b = float(aero_model.refc) / 2.0
    work = h_load * np.asarray(mesh.area, dtype=float)[:, None]   # G_kg^T S_kj (aero.gaf)
    n = slope.shape[1]
    steady = steady_aic(mesh, mach, symxz=aero_model.symxz)
    forces = work.T @ np.linalg.solve(steady, np.concatenate([slope, h_colloc / b], axis=1))
    unsteady = dlm_aic(mesh, mach, [k], refc=aero_model.refc, method=method,
                       symxz=aero_model.symxz)[0]
    # out-of-phase part of the response to the slope alone: the wake's lag (Etkin & Reid ch. 5)
    lag = (work.T @ np.linalg.solve(unsteady, slope.astype(complex))).imag / k
    return forces[:, :n], forces[:, n:], lag


def _derivatives(q0, q1_rate, q1_lag, s, aero_model, mach, reference_point, k,
                 dynamic_pressure=0.0) -> StabilityDerivatives:
    """Derivatives from the plunge / pitch block (rows lift, moment; column pitch)."""
    scale = np.array([s, s * aero_model.refc])
    (cl_a, cm_a), (cl_q, cm_q), (cl_ad, cm_ad) = (m[:2, 1] / scale for m in (q0, q1_rate, q1_lag))
    return StabilityDerivatives(cl_alpha=cl_a, cm_alpha=cm_a, cl_q=cl_q, cm_q=cm_q,
                                cl_alphadot=cl_ad, cm_alphadot=cm_ad, reference_area=s,
                                reference_chord=float(aero_model.refc),
                                reference_point=np.asarray(reference_point, dtype=float),
                                mach=float(mach), symxz=int(aero_model.symxz), k_alphadot=k,
                                dynamic_pressure=float(dynamic_pressure))


def _reference(aero_model, reference_point, reference_area):
    mesh = aero_model.mesh
    s = float(np.sum(np.asarray(mesh.area) * np.abs(np.asarray(mesh.normal)[:, 2]))) \
        if reference_area is None else float(reference_area)
    ref = aero_model.aero_frame.from_basic(np.asarray(reference_point, dtype=float))
    return s, rigid_box_motion(mesh, ref)


def stability_derivatives(aero_model, mach: float, reference_point, *,
                          reference_area: float | None = None, k_alphadot: float = K_ALPHADOT,
                          method: str = "quartic") -> StabilityDerivatives:
    """Longitudinal stability derivatives of the rigid aircraft (module docstring).

    Parameters
    ----------
    aero_model : aero.model.AeroModel
    mach : float
        Free-stream Mach number, 0 <= M < 1.
    reference_point : (3,) float
        Moment reference point (the CG, ``structures.massprops.mass_properties(model).cg``),
        basic frame.
    reference_area : float, optional
        S; default the planform area of the boxes, sum of area * |n_z| (the modelled half when
        SYMXZ = +1).
    k_alphadot : float
        Small reduced frequency k = omega b / V (b = REFC / 2) of the alpha-dot derivatives.
    method : {"quartic", "parabolic"}
        Doublet-lattice kernel integration.

    Returns
    -------
    StabilityDerivatives
    """
    s, motion = _reference(aero_model, reference_point, reference_area)
    q0, q1_rate, q1_lag = quasi_steady_forces(aero_model, mach, *motion, k=k_alphadot,
                                              method=method)
    return _derivatives(q0, q1_rate, q1_lag, s, aero_model, mach, reference_point, k_alphadot)


def flexible_derivatives(aero_model, modes_ds, mach: float, reference_point, dynamic_pressure, *,
                         rigid_hz: float = 0.05, reference_area: float | None = None,
                         k_alphadot: float = K_ALPHADOT,
                         method: str = "quartic") -> list[StabilityDerivatives]:
    """Stability derivatives of the elastic aircraft, its elastic modes in quasi-static equilibrium.

    The elastic modes e (in-vacuo frequency >= ``rigid_hz``) follow the rigid motion r (plunge,
    pitch) quasi-statically, K_e u_e = q (Q_er u_r + Q_ee u_e), and are eliminated (the
    "quasi-steady flexible vehicle" of Rodden & Love, J. Aircraft 22(9), 1985; Waszak & Schmidt,
    J. Aircraft 25(6), 1988, with the elastic inertia dropped)::

        A0 = Q0_rr + q Q0_re K^-1 Q0_er,                       K = K_e - q Q0_ee
        A1 = Q1_rr + q (Q1_re K^-1 Q0_er + Q0_re K^-1 Q1_er) + q^2 Q0_re K^-1 Q1_ee K^-1 Q0_er

    (A1 the first-order term of (K_e - q Q_ee(p))^-1 in p; the rate and lag parts of Q1 kept
    apart, :func:`quasi_steady_forces`). The derivatives follow from A0, A1 as in
    :func:`stability_derivatives`, which they equal at q = 0.

    Parameters
    ----------
    aero_model : aero.model.AeroModel
    modes_ds : xarray.Dataset
        The structure's modes (DESIGN.md section 6) on the deck of ``aero_model``; with SYMXZ = +1
        its symmetric modes. Rigid-body modes (below ``rigid_hz``) are not used: plunge and pitch
        are the exact rigid motions about ``reference_point``.
    mach, reference_point, reference_area, k_alphadot, method
        As :func:`stability_derivatives`.
    dynamic_pressure : array_like, shape (nq,)
        q = rho V^2 / 2, consistent units.
    rigid_hz : float
        In-vacuo frequency below which a mode is rigid (the contract's 0.05 Hz).

    Returns
    -------
    list of StabilityDerivatives
        One per dynamic pressure (its ``dynamic_pressure`` field set).
    """
    qd = np.atleast_1d(np.asarray(dynamic_pressure, dtype=float))
    if qd.ndim != 1 or not np.all(np.isfinite(qd)) or np.any(qd < 0):
        raise InputError(card_message(f"dynamic pressures {qd.tolist()} must be >= 0 and finite.",
                                      fix="give q = rho V^2 / 2 per speed."))
    freq = np.asarray(modes_ds["frequency"].values, dtype=float)
    elastic = freq >= rigid_hz
    if not elastic.any():
        raise InputError(card_message(
            f"no mode at or above rigid_hz = {rigid_hz} Hz in the modes Dataset "
            f"({modes_ds.attrs.get('source', '?')}).", fix="compute elastic modes too, or use "
                                                           "stability_derivatives."))
    s, rigid = _reference(aero_model, reference_point, reference_area)
    modal = modal_box_motion(aero_model, modes_ds.isel(mode=np.flatnonzero(elastic)))
    motion = [np.concatenate([r, e], axis=1) for r, e in zip(rigid, modal)]
    q0, q1_rate, q1_lag = quasi_steady_forces(aero_model, mach, *motion, k=k_alphadot,
                                              method=method)
    k_e = np.diag((2.0 * np.pi * freq[elastic]) ** 2
                  * np.asarray(modes_ds["generalized_mass"].values, dtype=float)[elastic])
    r, e = slice(0, 2), slice(2, None)
    out = []
    for q in qd:
        flex = np.linalg.solve(k_e - q * q0[e, e], np.concatenate([q0[e, r], np.eye(k_e.shape[0])],
                                                                   axis=1))
        kinv_er, kinv = flex[:, :2], flex[:, 2:]      # K^-1 Q0_er, K^-1
        a0 = q0[r, r] + q * q0[r, e] @ kinv_er
        a1 = [q1[r, r] + q * (q1[r, e] @ kinv_er + q0[r, e] @ kinv @ q1[e, r])
              + q * q * q0[r, e] @ kinv @ q1[e, e] @ kinv_er for q1 in (q1_rate, q1_lag)]
        out.append(_derivatives(a0, *a1, s, aero_model, mach, reference_point, k_alphadot, q))
    return out


def longitudinal_inertia(mass_props, aero_model) -> tuple[float, float]:
    """Mass and pitch inertia of a structural model for the rigid-body equations.

    Parameters
    ----------
    mass_props : structures.massprops.MassProperties
        Of the structure that carries ``aero_model`` (the same half when SYMXZ = +1).
    aero_model : aero.model.AeroModel

    Returns
    -------
    mass : float
    iyy : float
        Moment of inertia about the axis through the CG along the aerodynamic frame's y axis,
        I_yy = a_y^T I_cg a_y (a_y the unit y axis of ACSID in basic).
    """
    axis = np.asarray(aero_model.aero_frame.axes)[1]
    return float(mass_props.mass), float(axis @ np.asarray(mass_props.inertia) @ axis)
