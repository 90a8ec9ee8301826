"""State-space flutter cross-check: poles of the Roger-RFA aeroelastic model versus velocity.

At each velocity the LTI model of a Roger RFA (aero.rfa, passed in as data) gives all poles at
once (:func:`aeroelastic_statespace`: with q = rho V^2 / 2 and lag states
x_l = A_{l+2} s/(s + beta_l V/b) u the aeroelastic equations M u'' + B u' + K u = q Q u become a
linear time-invariant system, Karpel's arrangement, J. Aircraft 19(3), 1982, eq. 2-4); the
structural roots are followed from the in-vacuo modes by eigenvalue continuity and eigenvector
correlation (flutter.tracking), the aerodynamic lag poles are left out. Flutter is where a root's
g = 2 Re(p) / Im(p) crosses zero upward (linear interpolation between velocities). The result
differs from p-k only by the rational-approximation error (and p-k's harmonic assumption off the
imaginary axis), which is what makes it a cross-check.
"""
from __future__ import annotations

import control
import numpy as np
import xarray as xr

from flutter.crossings import find_brackets, interpolate_zero
from flutter.system import ModalSystem
from flutter.tracking import assign
from structures.common.errors import InputError


def aeroelastic_statespace(M: np.ndarray, B: np.ndarray, K: np.ndarray, rfa,
                           velocity: float, density: float) -> control.StateSpace:
    """LTI aeroelastic model at one flight point; states [u, u', x_1..x_L], outputs u.

    Parameters
    ----------
    M, B, K : ndarray, shape (n, n)
        Modal mass, damping, stiffness.
    rfa : aero.rfa.RogerRFA
        Its ``A`` (3 + nlag, n, n), ``beta`` (nlag,) and ``refc``.
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


def statespace_solve(system: ModalSystem, rfa, velocity, *, density: float) -> xr.Dataset:
    """Structural poles of the RFA state-space model along increasing velocities.

    Parameters
    ----------
    system : ModalSystem
        M_hh, B_hh, K_hh (structural damping is not modelled here).
    rfa : aero.rfa.RogerRFA
        From :func:`aero.rfa.fit_roger`.
    velocity : array_like, shape (nv,)
        Strictly increasing velocities.
    density : float

    Returns
    -------
    xarray.Dataset
        dims (velocity, root): ``eigenvalue``, ``damping`` (2 Re/Im), ``frequency`` [Hz]; crossings
        as ``crossing_velocity``, ``crossing_frequency``, ``crossing_root``.
    """
    V = np.asarray(velocity, dtype=float)
    if V.ndim != 1 or np.any(V <= 0) or np.any(np.diff(V) <= 0):
        raise InputError("statespace_solve: velocities must be positive and strictly increasing. "
                         "Fix: sort the velocity list.")
    n = system.n
    omega0, phi = system.in_vacuo()
    p_prev = 1j * omega0.astype(complex)
    u_prev = phi.T.astype(complex)
    P = np.zeros((V.size, n), dtype=complex)
    for i, v in enumerate(V):
        ss = aeroelastic_statespace(system.mass, system.damping, system.stiffness, rfa, v, density)
        lam, X = np.linalg.eig(ss.A)
        keep = lam.imag >= -1e-9 * np.abs(lam).max()
        lam, U = lam[keep], X[:n, keep].T
        order = assign(p_prev, u_prev, lam, U)
        p_prev, u_prev = lam[order], U[order]
        P[i] = p_prev
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.where(np.abs(P.imag) > 1e-9, 2 * P.real / P.imag, np.sign(P.real) * np.inf)
    rows = []
    for r, i in find_brackets(np.where(np.isfinite(g), g, np.nan_to_num(g, posinf=1.0, neginf=-1.0))):
        if np.isfinite(g[i, r]) and np.isfinite(g[i + 1, r]):
            t = interpolate_zero(g[i, r], g[i + 1, r])
            w = abs(P[i, r].imag) + t * (abs(P[i + 1, r].imag) - abs(P[i, r].imag))
            rows.append((r + 1, V[i] + t * (V[i + 1] - V[i]), w / (2 * np.pi)))
    return xr.Dataset(
        {"eigenvalue": (("velocity", "root"), P), "damping": (("velocity", "root"), g),
         "frequency": (("velocity", "root"), np.abs(P.imag) / (2 * np.pi), {"units": "Hz"}),
         "crossing_root": ("crossing", np.array([r[0] for r in rows], dtype=int)),
         "crossing_velocity": ("crossing", np.array([r[1] for r in rows], dtype=float)),
         "crossing_frequency": ("crossing", np.array([r[2] for r in rows], dtype=float))},
        coords={"velocity": V, "root": np.arange(1, n + 1)},
        attrs={"method": "state-space (Roger RFA)", "rfa_fit_error": rfa.fit_error,
               "lags": rfa.beta.tolist()},
    )
