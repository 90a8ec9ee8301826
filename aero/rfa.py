"""Roger rational function approximation of Q_hh(ik).

Roger, K. L., "Airplane Math Modeling Methods for Active Control Design", AGARD-CP-228, 1977:

    Q(p_bar) ~ A0 + A1 p_bar + A2 p_bar^2 + sum_l A_{l+2} p_bar / (p_bar + beta_l),
    p_bar = s b / V  (= i k on the imaginary axis; k = omega b / V, b = REFC / 2),

fitted by linear least squares to the tabulated Q(ik) of one Mach number, all matrix entries at
once. The aeroelastic state-space model built on it (structure + RFA, a flutter cross-check) is
:func:`flutter.statespace.aeroelastic_statespace`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from structures.common.errors import InputError


@dataclass(frozen=True)
class RogerRFA:
    """A fitted Roger approximation at one Mach number.

    Attributes
    ----------
    A : ndarray, shape (3 + nlag, n, n)
        A0, A1, A2 and the lag matrices.
    beta : ndarray, shape (nlag,)
        Lag roots (reduced-frequency units).
    refc : float
        Reference chord (b = refc / 2).
    mach : float
    fit_error : float
        max |Q_fit - Q| / max |Q| over the tabulated k.
    """

    A: np.ndarray
    beta: np.ndarray
    refc: float
    mach: float
    fit_error: float

    def evaluate(self, k: np.ndarray) -> np.ndarray:
        """Q_fit(ik), shape (nk, n, n), at reduced frequencies ``k``."""
        return np.einsum("kt,tij->kij", _basis(np.atleast_1d(np.asarray(k, float)), self.beta), self.A)


def _basis(k: np.ndarray, beta: np.ndarray) -> np.ndarray:
    p = 1j * k[:, None]
    return np.concatenate([np.ones_like(p), p, p * p, p / (p + beta[None, :])], axis=1)


def fit_roger(gaf: xr.Dataset, mach: float, beta=None, nlag: int = 4) -> RogerRFA:
    """Least-squares Roger fit of ``gaf.Q`` at one tabulated Mach number.

    Parameters
    ----------
    gaf : xarray.Dataset
        ``Q(mach, k, mode_i, mode_j)`` with attrs ``refc``.
    mach : float
        A tabulated Mach number.
    beta : array_like, optional
        Lag roots; default ``nlag`` values geometrically spaced over the tabulated k range
        (between the second-smallest k and 0.8 x the largest).
    nlag : int
        Number of lags when ``beta`` is not given.

    Returns
    -------
    RogerRFA
    """
    machs = np.asarray(gaf["mach"].values, dtype=float)
    j = np.flatnonzero(np.isclose(machs, mach, atol=1e-6))
    if j.size == 0:
        raise InputError(f"fit_roger: Mach {mach} is not tabulated ({machs.tolist()}). Fix: fit at "
                         "one of the GAF Mach numbers.")
    Q = np.asarray(gaf["Q"].transpose("mach", "k", "mode_i", "mode_j").values[j[0]], dtype=complex)
    k = np.asarray(gaf["k"].values, dtype=float)
    if beta is None:
        kpos = np.sort(k[k > 0])
        beta = np.geomspace(kpos[min(1, kpos.size - 1)], 0.8 * kpos[-1], nlag)
    beta = np.asarray(beta, dtype=float)
    if np.any(beta <= 0):
        raise InputError("fit_roger: lag roots must be > 0. Fix: pass positive beta values.")
    if k.size < 3 + beta.size:
        raise InputError(f"fit_roger: {k.size} reduced frequencies cannot fit {3 + beta.size} "
                         "coefficient matrices. Fix: use fewer lags or more MKAERO1 k values.")
    n = Q.shape[-1]
    E = _basis(k, beta)                                   # (nk, nt) complex
    Er = np.concatenate([E.real, E.imag])                 # real least squares, Roger eq. (9)
    rhs = Q.reshape(k.size, n * n)
    Rr = np.concatenate([rhs.real, rhs.imag])
    coef, *_ = np.linalg.lstsq(Er, Rr, rcond=None)
    A = coef.reshape(-1, n, n)
    err = float(np.abs(np.einsum("kt,tij->kij", E, A) - Q).max() / np.abs(Q).max())
    return RogerRFA(A=A, beta=beta, refc=float(gaf.attrs["refc"]), mach=float(mach), fit_error=err)
