"""The rigid aircraft free in plunge and pitch: the classical short-period characteristic equation.

An independent check of the rigid-body roots of the flutter methods from flight mechanics (Etkin &
Reid, *Dynamics of Flight: Stability and Control*, 3rd ed., 1996, ch. 4 (linearised longitudinal
equations) and ch. 6 (the short-period mode); Nelson, *Flight Stability and Automatic Control*,
2nd ed., 1998, ch. 4). Like the flutter models it has no gravity and no speed change, so the
longitudinal motion of the rigid aircraft reduces to the angle of attack alpha and the pitch rate q
plus two integrals: the pitch attitude theta (theta' = q) and the plunge h (h' = V (theta - alpha)),
whose roots are exactly zero (flight-path angle and altitude: any steady climb angle and any
altitude are equilibria). With lift L = q_dyn S C_L along +z, moment M = q_dyn S c C_m and
c_hat = c / (2 V) (sign conventions and derivatives: :mod:`aero.stability`)::

    m V (q - alpha') = q_dyn S [C_L_alpha alpha + c_hat C_L_q q + c_hat C_L_alphadot alpha']
    I_yy q'          = q_dyn S c [C_m_alpha alpha + c_hat C_m_q q + c_hat C_m_alphadot alpha']

i.e. E [alpha', q']^T = A [alpha, q]^T, whose two eigenvalues are the short period. The alpha-dot
terms act on alpha' = q - h''/V: the lag of the downwash responds to a plunge acceleration as to a
pitch rate (``alphadot="alpha"``, the flight-mechanics model). ``alphadot="pitch_rate"`` applies
them to q only: the truncation Q(p_bar) = Q0 + p_bar Q1 of the modal generalized forces of plunge
and pitch (the quasi-steady p-method), which drops the p_bar^2 term -(p_bar^2 / b) Q_alpha,1 of the
plunge column that the alpha-dot derivatives carry.

Roots follow the flutter conventions (flutter package docstring): p = omega (gamma + i) with
Im p >= 0, g = 2 Re p / Im p for oscillatory roots and Nastran's g = p c / (V ln 2) for real
roots, c = REFC.
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from structures.common.errors import InputError, card_message

__all__ = ["ALPHADOT_MODELS", "ROOT_LABELS", "short_period", "short_period_approximation"]

ALPHADOT_MODELS = ("alpha", "pitch_rate")
#: Labels of the four roots of the plunge-pitch characteristic equation (Dataset coordinate).
ROOT_LABELS = ("short period", "short period", "flight-path angle", "altitude")
_DERIVATIVES = ("cl_alpha", "cm_alpha", "cl_q", "cm_q", "cl_alphadot", "cm_alphadot")


def _inputs(derivs, mass, iyy, rho, velocity):
    """Velocities (nv,), the derivatives as arrays (nv,) -- one object for every speed or one per
    speed -- and the reference area and chord."""
    v = np.atleast_1d(np.asarray(velocity, dtype=float))
    if v.ndim != 1 or v.size == 0 or not np.all(np.isfinite(v)) or np.any(v <= 0):
        raise InputError(card_message(f"short_period: velocities {v.tolist()} must be a non-empty "
                                      "1-D list of positive values.", fix="e.g. [30., 60.]."))
    items = list(derivs) if isinstance(derivs, (list, tuple)) else [derivs] * v.size
    if len(items) != v.size:
        raise InputError(card_message(f"short_period: {len(items)} sets of derivatives for "
                                      f"{v.size} velocities.", fix="give one set, or one per "
                                                                   "velocity."))
    for item in items:
        missing = [n for n in (*_DERIVATIVES, "reference_area", "reference_chord")
                   if not hasattr(item, n)]
        if missing:
            raise InputError(card_message(
                f"short_period: the derivatives object lacks {missing}.",
                fix="pass an aero.stability.StabilityDerivatives."))
    refs = {(float(i.reference_area), float(i.reference_chord)) for i in items}
    if len(refs) != 1:
        raise InputError(card_message(f"short_period: the derivatives use different reference "
                                      f"areas / chords {sorted(refs)}.", fix="compute them all "
                                                                             "on one S and c."))
    for name, value in (("mass", mass), ("iyy", iyy), ("rho", rho)):
        if not 0 < float(value) < np.inf:
            raise InputError(card_message(f"short_period: {name}={value} must be positive and "
                                          "finite.", fix=f"give the aircraft's {name} in the "
                                                         "deck's consistent units."))
    values = {n: np.array([float(getattr(i, n)) for i in items]) for n in _DERIVATIVES}
    area, chord = refs.pop()
    return v, values, area, chord


def _dimensional(area, chord, rho, v):
    """q_dyn S, q_dyn S c and c_hat per velocity (each shape (nv,))."""
    qs = 0.5 * float(rho) * v * v * area
    return qs, qs * chord, chord / (2.0 * v)


def short_period(derivs, mass: float, iyy: float, rho: float, velocity, *,
                 alphadot: str = "alpha") -> xr.Dataset:
    """Roots of the plunge-pitch characteristic equation of a rigid aircraft (module docstring).

    Parameters
    ----------
    derivs : aero.stability.StabilityDerivatives, or a list of them, shape (nv,)
        About the CG (any object with the derivative and reference attributes): one set for every
        speed (rigid aircraft), or one per speed (``aero.stability.flexible_derivatives`` at each
        speed's dynamic pressure), all on the same S and c.
    mass : float
        Aircraft mass (the half model's with SYMXZ = +1 derivatives), consistent units.
    iyy : float
        Pitch moment of inertia about the CG.
    rho : float
        Air density.
    velocity : array_like, shape (nv,)
        True airspeeds.
    alphadot : {"alpha", "pitch_rate"}
        What the alpha-dot derivatives multiply: alpha' (flight mechanics) or q only (the
        quasi-steady modal truncation).

    Returns
    -------
    xarray.Dataset
        On (velocity, root), root 1..4 with ``root_label`` (:data:`ROOT_LABELS`): ``eigenvalue``
        p [rad/s] (Im p >= 0), ``frequency`` [Hz], ``damping`` g, ``k`` = Im p b / V. Roots 1 and 2
        are the short period: the same p when it oscillates, its two real roots (root 1 the
        slower) when it does not; roots 3 and 4 are exactly zero. attrs: units, ``alphadot``,
        ``refc``, conventions.
    """
    if alphadot not in ALPHADOT_MODELS:
        raise InputError(card_message(f"short_period: alphadot={alphadot!r} unknown.",
                                      fix=f"use one of {ALPHADOT_MODELS}."))
    v, d, area, chord = _inputs(derivs, mass, iyy, rho, velocity)
    qs, qsc, c_hat = _dimensional(area, chord, rho, v)
    on_alpha = 1.0 if alphadot == "alpha" else 0.0
    E = np.zeros((v.size, 2, 2))
    A = np.zeros((v.size, 2, 2))
    # E [alpha', q'] = A [alpha, q] (Etkin & Reid ch. 4, no gravity, no speed change)
    E[:, 0, 0] = mass * v + on_alpha * qs * c_hat * d["cl_alphadot"]
    E[:, 1, 0] = -on_alpha * qsc * c_hat * d["cm_alphadot"]
    E[:, 1, 1] = iyy
    A[:, 0, 0] = -qs * d["cl_alpha"]
    A[:, 0, 1] = mass * v - qs * c_hat * (d["cl_q"] + (1.0 - on_alpha) * d["cl_alphadot"])
    A[:, 1, 0] = qsc * d["cm_alpha"]
    A[:, 1, 1] = qsc * c_hat * (d["cm_q"] + (1.0 - on_alpha) * d["cm_alphadot"])
    if np.any(E[:, 0, 0] <= 0):
        raise InputError(card_message(
            f"short_period: m V + q S c/(2V) C_L_alphadot <= 0 at V = "
            f"{v[E[:, 0, 0] <= 0].tolist()} (C_L_alphadot = {d['cl_alphadot'].tolist()}).",
            fix="check the derivatives and the mass units (the half model's mass with "
                "half-model derivatives)."))
    sp = np.linalg.eigvals(np.linalg.solve(E, A))                      # (nv, 2)
    real = np.abs(sp.imag) <= 1e-12 * np.abs(sp).max(axis=1, keepdims=True)
    sp = np.where(real, sp.real + 0j, sp.real + 1j * np.abs(sp.imag))
    order = np.argsort(-sp.real, axis=1, kind="stable")                # real pair: slower first
    sp = np.take_along_axis(sp, order, axis=1)
    p = np.concatenate([sp, np.zeros((v.size, 2), dtype=complex)], axis=1)
    oscillating = p.imag > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.where(oscillating, 2.0 * p.real / np.where(oscillating, p.imag, 1.0),
                     p.real * chord / (v[:, None] * np.log(2.0)))
    b = chord / 2.0
    dims = ("velocity", "root")
    ds = xr.Dataset(
        {"eigenvalue": (dims, p), "frequency": (dims, p.imag / (2.0 * np.pi)),
         "damping": (dims, g), "k": (dims, p.imag * b / v[:, None])},
        coords={"velocity": v, "root": np.arange(1, 5), "root_label": ("root", list(ROOT_LABELS))},
        attrs={"method": "stability derivatives", "alphadot": alphadot, "refc": chord,
               "density": float(rho), "mass": float(mass), "iyy": float(iyy),
               "conventions": "p = omega (gamma + i), Im p >= 0; g = 2 Re p / Im p, real roots "
                              "g = p c / (V ln 2); k = omega b / V, b = refc / 2"})
    ds["eigenvalue"].attrs["units"] = "rad/s"
    ds["frequency"].attrs["units"] = "Hz"
    ds["damping"].attrs["units"] = "1 (g = 2 zeta)"
    ds["k"].attrs["units"] = "1"
    ds["velocity"].attrs["units"] = "model length unit / s"
    return ds


def short_period_approximation(derivs, mass: float, iyy: float, rho: float,
                               velocity) -> tuple[np.ndarray, np.ndarray]:
    """The textbook short-period approximation (Nelson ch. 4; Etkin & Reid ch. 6).

    omega_sp^2 = Z_alpha M_q / V - M_alpha and 2 zeta_sp omega_sp = -(M_q + M_alphadot +
    Z_alpha / V), with Z_alpha = -q_dyn S C_L_alpha / m, M_alpha = q_dyn S c C_m_alpha / I_yy,
    M_q = q_dyn S c C_m_q c_hat / I_yy, M_alphadot = q_dyn S c C_m_alphadot c_hat / I_yy. It
    neglects C_L_q and C_L_alphadot against m V (large relative density 2 m / (rho S c)); then it
    equals :func:`short_period` with ``alphadot="alpha"``.

    Parameters
    ----------
    As :func:`short_period`.

    Returns
    -------
    omega_sp : ndarray, shape (nv,)
        Undamped natural frequency [rad/s] (nan where omega_sp^2 <= 0: statically unstable).
    zeta_sp : ndarray, shape (nv,)
        Damping ratio (g = 2 zeta for light damping).
    """
    v, d, area, chord = _inputs(derivs, mass, iyy, rho, velocity)
    qs, qsc, c_hat = _dimensional(area, chord, rho, v)
    z_alpha = -qs * d["cl_alpha"] / mass
    m_alpha = qsc * d["cm_alpha"] / iyy
    m_q = qsc * d["cm_q"] * c_hat / iyy
    m_alphadot = qsc * d["cm_alphadot"] * c_hat / iyy
    omega2 = z_alpha * m_q / v - m_alpha
    omega = np.sqrt(np.where(omega2 > 0, omega2, np.nan))
    return omega, -(m_q + m_alphadot + z_alpha / v) / (2.0 * omega)
