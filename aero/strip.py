"""Theodorsen strip aerodynamics for 2-D sections and high-aspect-ratio wings.

Incompressible thin-airfoil unsteady theory (Theodorsen 1935, NACA Report 496; as written in
Bisplinghoff, Ashley & Halfman, *Aeroelasticity*, 1955, eqs. 5-311/5-312, and Hodges & Pierce,
*Introduction to Structural Dynamics and Aeroelasticity*, 2nd ed., 2011, eqs. 5.303-5.304).

Section degrees of freedom: plunge ``h`` (positive DOWN, length) and pitch ``alpha`` (positive nose UP,
rad) about the elastic axis located ``a`` semichords aft of mid-chord. The generalized aerodynamic
forces follow Nastran's QHH convention: ``F = q * Q(k) @ u`` with ``q = rho V^2 / 2``, ``u = [h, alpha]``
and ``F = [-L, M_alpha]`` (work conjugates of ``h`` and ``alpha``), for harmonic motion ``u e^{i omega t}``.

Reduced frequency everywhere is Nastran's k = omega * b / V, b the semichord (REFC / 2).
"""
from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.special import hankel2

from structures.common.errors import InputError


def theodorsen(k: np.ndarray | float) -> np.ndarray:
    """Theodorsen's lift-deficiency function C(k) = F + iG.

    Parameters
    ----------
    k : array_like, shape (...)
        Reduced frequency k = omega * b / V (b = semichord), k >= 0.

    Returns
    -------
    C : ndarray of complex, shape (...)
        C(k) = H1^(2)(k) / (H1^(2)(k) + i H0^(2)(k)) (Theodorsen 1935; BAH eq. 5-314); C(0) = 1.
    """
    k = np.asarray(k, dtype=float)
    if np.any(k < 0) or not np.all(np.isfinite(k)):
        raise InputError("theodorsen: reduced frequency k must be finite and >= 0. "
                         "Fix: pass k = omega*b/V >= 0.")
    out = np.ones(k.shape, dtype=complex)
    pos = k > 0
    kk = k[pos]
    h1 = hankel2(1, kk)
    h0 = hankel2(0, kk)
    out[pos] = h1 / (h1 + 1j * h0)  # Theodorsen 1935 eq. (VIII); BAH eq. 5-314
    return out


def section_gaf(k: np.ndarray | float, a: float, b: float = 1.0,
                lift_slope: float = 2.0 * np.pi) -> np.ndarray:
    """Theodorsen generalized aerodynamic force matrix of a 2-D section, per unit span.

    Parameters
    ----------
    k : array_like, shape (nk,) or scalar
        Section reduced frequency k = omega * b / V.
    a : float
        Elastic-axis position aft of mid-chord, in semichords (Theodorsen's ``a``).
    b : float
        Semichord (length units of the model).
    lift_slope : float
        Circulatory lift-curve slope per radian; 2*pi is thin-airfoil theory. It scales only the
        circulatory terms (the usual strip-theory correction).

    Returns
    -------
    Q : ndarray of complex, shape (nk, 2, 2) (or (2, 2) for scalar k)
        ``F = q Q u`` with u = [h, alpha], F = [-L, M_alpha], q = rho V^2 / 2.

    Notes
    -----
    With harmonic motion, hdot = i k V/b h and hddot = -(k V/b)^2 h, Theodorsen's (BAH eq. 5-311)
        L = pi rho b^2 (hddot + V alphadot - b a alphaddot)
            + 2 pi rho V b C(k) [V alpha + hdot + b (1/2 - a) alphadot]
        M = pi rho b^2 [b a hddot - V b (1/2 - a) alphadot - b^2 (1/8 + a^2) alphaddot]
            + 2 pi rho V b^2 (a + 1/2) C(k) [V alpha + hdot + b (1/2 - a) alphadot]
    divided by q = rho V^2 / 2 give the entries below.
    """
    scalar = np.ndim(k) == 0
    k = np.atleast_1d(np.asarray(k, dtype=float))
    if b <= 0:
        raise InputError(f"section_gaf: semichord b={b} must be > 0. Fix: pass b = chord/2 > 0.")
    C = theodorsen(k) * (lift_slope / (2.0 * np.pi))
    ik = 1j * k
    k2 = k * k
    pi = np.pi
    # lift per (rho V^2): coefficients of h and alpha (BAH eq. 5-311 with harmonic motion)
    L_h = -pi * k2 + 2.0 * pi * C * ik
    L_a = b * (pi * ik + pi * a * k2 + 2.0 * pi * C * (1.0 + (0.5 - a) * ik))
    # pitching moment per (rho V^2) (BAH eq. 5-312)
    M_h = b * (-pi * a * k2 + 2.0 * pi * (a + 0.5) * C * ik)
    M_a = b * b * (-pi * (0.5 - a) * ik + pi * (0.125 + a * a) * k2
                   + 2.0 * pi * (a + 0.5) * C * (1.0 + (0.5 - a) * ik))
    Q = np.empty(k.shape + (2, 2), dtype=complex)
    Q[:, 0, 0] = -2.0 * L_h  # generalized force on h is -L (h positive down)
    Q[:, 0, 1] = -2.0 * L_a
    Q[:, 1, 0] = 2.0 * M_h
    Q[:, 1, 1] = 2.0 * M_a
    return Q[0] if scalar else Q


def strip_gaf(k: np.ndarray, *, y: np.ndarray, width: np.ndarray, semichord: np.ndarray,
              a: np.ndarray, plunge: np.ndarray, pitch: np.ndarray, refc: float,
              rhoref: float = 1.0, mach: float = 0.0,
              lift_slope: float = 2.0 * np.pi) -> xr.Dataset:
    """Strip-theory GAFs of a high-aspect-ratio wing from section Theodorsen forces.

    Each strip j (width dy_j, semichord b_j, elastic axis a_j) moves with the plunge h_j(mode) and
    pitch alpha_j(mode) of each mode; the strip reduced frequency is k_j = k * b_j / b_ref.

    Parameters
    ----------
    k : array_like, shape (nk,)
        Reference reduced frequencies k = omega * b_ref / V, b_ref = refc / 2.
    y, width, semichord, a : array_like, shape (ns,)
        Strip span station (kept as a coordinate), width, semichord and elastic-axis position
        (semichords aft of mid-chord).
    plunge, pitch : array_like, shape (nmode, ns)
        Modal plunge (positive down) and pitch (nose up, rad) at each strip's elastic axis.
    refc, rhoref : float
        Reference chord (b_ref = refc/2) and reference density (attrs, as Nastran's AERO card).
    mach : float
        Mach label of the result (the theory is incompressible).
    lift_slope : float
        Circulatory lift-curve slope per radian.

    Returns
    -------
    xarray.Dataset
        ``Q(mach, k, mode_i, mode_j)`` complex, attrs ``refc``, ``rhoref``; the GAF contract of
        DESIGN.md section 6 (generalized force = q * Q @ u).
    """
    k = np.atleast_1d(np.asarray(k, dtype=float))
    y, width, semichord, a = (np.atleast_1d(np.asarray(v, dtype=float)) for v in (y, width, semichord, a))
    plunge = np.atleast_2d(np.asarray(plunge, dtype=float))
    pitch = np.atleast_2d(np.asarray(pitch, dtype=float))
    ns = y.size
    if not (width.size == semichord.size == a.size == ns and plunge.shape == pitch.shape
            and plunge.shape[1] == ns):
        raise InputError(f"strip_gaf: inconsistent strip arrays (y {y.shape}, width {width.shape}, "
                         f"semichord {semichord.shape}, a {a.shape}, plunge {plunge.shape}, "
                         f"pitch {pitch.shape}). Fix: one value per strip, modes as rows.")
    if refc <= 0:
        raise InputError(f"strip_gaf: refc={refc} must be > 0. Fix: pass the reference chord.")
    bref = refc / 2.0
    nmode = plunge.shape[0]
    Q = np.zeros((k.size, nmode, nmode), dtype=complex)
    for j in range(ns):
        Qs = section_gaf(k * semichord[j] / bref, a[j], semichord[j], lift_slope)  # (nk,2,2)
        phi = np.stack([plunge[:, j], pitch[:, j]], axis=0)  # (2, nmode)
        Q += width[j] * np.einsum("im,kij,jn->kmn", phi, Qs, phi)
    modes = np.arange(1, nmode + 1)
    return xr.Dataset(
        {"Q": (("mach", "k", "mode_i", "mode_j"), Q[None])},
        coords={"mach": [float(mach)], "k": k, "mode_i": modes, "mode_j": modes},
        attrs={"refc": float(refc), "rhoref": float(rhoref), "source": "Theodorsen strip theory",
               "k_convention": "k = omega*b/V, b = refc/2",
               "units": "generalized force per unit dynamic pressure"},
    )
