"""Roger rational function approximation of Q_hh(ik) and its state-space aeroelastic model.

Roger, K. L., "Airplane Math Modeling Methods for Active Control Design", AGARD-CP-228, 1977:

    Q(p_bar) ~ A0 + A1 p_bar + A2 p_bar^2 + sum_l A_{l+2} p_bar / (p_bar + beta_l),
    p_bar = s b / V  (= i k on the imaginary axis; k = omega b / V, b = REFC / 2),

fitted by linear least squares to the tabulated Q(ik) of one Mach number, all matrix entries at
once. With q = rho V^2 / 2 and lag states x_l = A_{l+2} s/(s + beta_l V/b) u the aeroelastic
equations M u'' + B u' + K u = q Q u become a linear time-invariant system (Karpel's arrangement,
J. Aircraft 19(3), 1982, eq. 2-4), returned as a python-control StateSpace.
"""
from __future__ import annotations

from dataclasses import dataclass

import control
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


def aeroelastic_statespace(M: np.ndarray, B: np.ndarray, K: np.ndarray, rfa: RogerRFA,
                           velocity: float, density: float) -> control.StateSpace:
    """LTI aeroelastic model at one flight point; states [u, u', x_1..x_L], outputs u.

    Parameters
    ----------
    M, B, K : ndarray, shape (n, n)
        Modal mass, damping, stiffness.
    rfa : RogerRFA
    velocity, density : float
        Flight point (model units).

    Returns
    -------
    control.StateSpace
        With a single zero input (the model is autonomous; poles are the flutter roots).
    """
    n = M.shape[0]
    b = rfa.refc / 2.0
    q = 0.5 * density * velocity ** 2
    L = rfa.beta.size
    Mbar = M - q * (b / velocity) ** 2 * rfa.A[2]      # Karpel 1982 eq. 4
    Bbar = B - q * (b / velocity) * rfa.A[1]
    Kbar = K - q * rfa.A[0]
    Mi = np.linalg.inv(Mbar)
    N = n * (2 + L)
    Amat = np.zeros((N, N))
    Amat[:n, n:2 * n] = np.eye(n)
    Amat[n:2 * n, :n] = -Mi @ Kbar
    Amat[n:2 * n, n:2 * n] = -Mi @ Bbar
    for l in range(L):
        sl = slice((2 + l) * n, (3 + l) * n)
        Amat[n:2 * n, sl] = q * Mi
        Amat[sl, n:2 * n] = rfa.A[3 + l]               # x_l' = A_l u' - beta_l V/b x_l
        Amat[sl, sl] = -(velocity / b) * rfa.beta[l] * np.eye(n)
    C = np.zeros((n, N))
    C[:, :n] = np.eye(n)
    return control.ss(Amat, np.zeros((N, 1)), C, np.zeros((n, 1)))
