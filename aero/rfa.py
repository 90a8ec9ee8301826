"""Rational function approximation of Q_hh(ik): Roger's form with real and complex-conjugate lags.

Roger, K. L., "Airplane Math Modeling Methods for Active Control Design", AGARD-CP-228, 1977, eq. 9,
extended with second-order lag terms: a pair of Roger lags p / (p + sigma -+ i w) with
complex-conjugate coefficients, written with real matrices (C_j, S_j) (real in the time domain,
stable for sigma > 0):

    Q(p) ~ A0 + A1 p + A2 p^2 + sum_l A_{3+l} p / (p + beta_l)
           + sum_j [ C_j p (p + sigma_j) + S_j w_j p ] / ((p + sigma_j)^2 + w_j^2),

p = s b / V (= i k on the imaginary axis; k = omega b / V, b = REFC / 2). Real lags alone describe
monotone lag behaviour only; Nastran's DLM GAFs of a whole aircraft also oscillate in k (wing-tail
downwash delays), which the complex pairs capture: on bah_plane's QHH at Mach 0.2, k <= 5, the
strict per-entry error (below) is 28 % with 4 optimised real lags and 0.5 % with 4 real lags plus
3 pairs (over all 15 tabulated k, up to 10, it is 14 %: the sparse table above k = 5 is not fitted
to 2 % entry by entry; overall error 1 %).

The fit is linear least squares in the coefficient matrices for given lag roots (all entries share
the basis, so each entry has its own least squares), subject to matching the smallest tabulated k
exactly: Re Q and Im Q / k there fix Q(0) and the k -> 0 slope to O(k_min^2) (the short period
lives at k ~ 0.04, where a free fit errs most). Each entry's residual is weighted by 1 / max_k
|Q_ij| (entries whose maximum is below ``floor`` x max |Q| are aerodynamically empty and weighted
as if at that floor), and the lag roots are optimised by variable projection (Golub & Pereyra, SIAM
J. Numer. Anal. 10(2), 1973: the coefficients are eliminated, the residual minimised over the
log-roots by scipy.optimize.least_squares from several starts; the start with the smallest strict
error is kept).

Fit error measures (over the fitted k, k <= ``k_max``):
``entry_error[i, j] = max_k |Q_fit - Q|_ij / max_k |Q_ij|`` (empty entries: 0), ``fit_error`` its
maximum (the strict measure), ``overall_error = max |Q_fit - Q| / max |Q|``.

Every fit has the descriptor form Q(p) = A0 + A1 p + A2 p^2 + D (p I - R)^-1 E p (Karpel's
minimum-state arrangement, J. Aircraft 19(3), 1982, eq. 2), which the p-method
(flutter.pmethod) turns into a state-space model: :meth:`RationalFit.descriptor`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr
from scipy.linalg import null_space
from scipy.optimize import least_squares
from threadpoolctl import threadpool_limits

from structures.common.errors import InputError

STARTS = 6          # optimiser starts: geometric spacing, then seeded random log-uniform roots
FLOOR = 1e-6        # entries below FLOOR * max|Q| are aerodynamically empty


@dataclass(frozen=True)
class RationalFit:
    """A fitted rational approximation of Q_hh at one Mach number.

    Attributes
    ----------
    A : ndarray, shape (3 + nlag + 2 npair, n, n)
        A0, A1, A2, the real-lag matrices, then (C_j, S_j) of each pair.
    beta : ndarray, shape (nlag,)
        Real lag roots (reduced-frequency units).
    pairs : ndarray, shape (npair, 2)
        (sigma_j, w_j) of each complex lag pair -sigma_j +- i w_j.
    refc : float
        Reference chord (b = refc / 2).
    mach : float
    k : ndarray, shape (nk,)
        The reduced frequencies fitted (k <= k_max).
    entry_error : ndarray, shape (n, n)
        max_k |Q_fit - Q| / max_k |Q_ij| per entry (0 for empty entries).
    fit_error : float
        Maximum of ``entry_error``.
    overall_error : float
        max |Q_fit - Q| / max |Q| over the fitted k.
    """

    A: np.ndarray
    beta: np.ndarray
    pairs: np.ndarray
    refc: float
    mach: float
    k: np.ndarray
    entry_error: np.ndarray
    fit_error: float
    overall_error: float

    @property
    def k_max(self) -> float:
        """Largest fitted reduced frequency."""
        return float(self.k.max())

    def evaluate(self, k: np.ndarray) -> np.ndarray:
        """Q_fit(ik), shape (nk, n, n), at reduced frequencies ``k`` (shape (nk,))."""
        E = _basis(1j * np.atleast_1d(np.asarray(k, dtype=float)), self.beta, self.pairs)
        return np.einsum("kt,tij->kij", E, self.A)

    def descriptor(self) -> tuple[np.ndarray, ...]:
        """The fit as Q(p) = A0 + A1 p + A2 p^2 + D (p I - R)^-1 E p (Karpel 1982, eq. 2).

        Returns
        -------
        A0, A1, A2 : ndarray, shape (n, n)
        D : ndarray, shape (n, m)
        R : ndarray, shape (m, m)
        E : ndarray, shape (m, n)
            With m = n (nlag + 2 npair) lag states: a real lag x = p / (p + beta) u has R = -beta I,
            E = I, D = A_l; a pair's states z = (p I - G)^-1 [I; 0] p u, G = [[-sigma, w], [-w,
            -sigma]] (x) I, give z1 = p (p + sigma) / d u and z2 = -w p / d u, so D = [C, -S].
        """
        n = self.A.shape[1]
        I = np.eye(n)
        Ds, Rs, Es = [], [], []
        for l, beta in enumerate(self.beta):
            Ds.append(self.A[3 + l])
            Rs.append(-beta * I)
            Es.append(I)
        for j, (sigma, w) in enumerate(self.pairs):
            C, S = self.A[3 + self.beta.size + 2 * j], self.A[4 + self.beta.size + 2 * j]
            Ds.append(np.hstack([C, -S]))
            Rs.append(np.block([[-sigma * I, w * I], [-w * I, -sigma * I]]))
            Es.append(np.vstack([I, np.zeros((n, n))]))
        m = sum(r.shape[0] for r in Rs)
        R = np.zeros((m, m))
        at = 0
        for block in Rs:
            R[at:at + block.shape[0], at:at + block.shape[0]] = block
            at += block.shape[0]
        D = np.hstack(Ds) if Ds else np.zeros((n, 0))
        E = np.vstack(Es) if Es else np.zeros((0, n))
        return self.A[0], self.A[1], self.A[2], D, R, E


def _basis(p: np.ndarray, beta: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """Basis functions of the fit at p = i k, shape (nk, 3 + nlag + 2 npair)."""
    p = p[:, None]
    cols = [np.ones_like(p), p, p * p, p / (p + beta[None, :])]
    for sigma, w in pairs:
        d = (p + sigma) ** 2 + w ** 2
        cols += [p * (p + sigma) / d, w * p / d]
    return np.concatenate(cols, axis=1)


def _solve(k: np.ndarray, Q: np.ndarray, weight: np.ndarray, beta: np.ndarray,
           pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients for given lag roots: weighted least squares with Q matched at k[0].

    Returns the coefficient matrices (nt, n, n) and the weighted residual (nk, n, n) complex.
    """
    n = Q.shape[-1]
    E = _basis(1j * k, beta, pairs)                          # (nk, nt)
    C = np.concatenate([E[:1].real, E[:1].imag])             # Q_fit(i k_min) = Q(k_min): 2 rows
    d = np.concatenate([Q[:1].real, Q[:1].imag]).reshape(2, n * n)
    A_p = np.linalg.lstsq(C, d, rcond=None)[0]
    N = null_space(C)
    Er = np.concatenate([E.real, E.imag])                    # Roger eq. 9, real and imaginary rows
    R = np.concatenate([Q.real, Q.imag]).reshape(2 * k.size, n * n)
    z = np.linalg.lstsq(Er @ N, R - Er @ A_p, rcond=None)[0]
    A = (A_p + N @ z).reshape(-1, n, n)
    return A, (np.einsum("kt,tij->kij", E, A) - Q) * weight


def fit_rfa(k, Q, *, refc: float, mach: float = float("nan"), nlag: int = 4, npair: int = 3,
            beta=None, pairs=None, k_max: float | None = None, floor: float = FLOOR,
            starts: int = STARTS) -> RationalFit:
    """Fit the rational approximation to tabulated Q(ik) of one Mach number.

    Parameters
    ----------
    k : array_like, shape (nk,)
        Reduced frequencies k = omega b / V (b = refc / 2), all > 0.
    Q : array_like, shape (nk, n, n) complex
        Q_hh at those k.
    refc : float
        Reference chord.
    mach : float
        Mach number (recorded).
    nlag, npair : int
        Numbers of real lags and complex lag pairs to optimise (ignored where ``beta`` / ``pairs``
        are given).
    beta : array_like, shape (nlag,), optional
        Fixed real lag roots (> 0); with ``pairs`` given too (or npair = 0) nothing is optimised.
    pairs : array_like, shape (npair, 2), optional
        Fixed (sigma, w) of complex pairs (sigma > 0, w > 0).
    k_max : float, optional
        Fit only the tabulated k <= k_max (the range the roots reach); default all.
    floor : float
        Entries with max |Q_ij| below floor x max |Q| are empty (see module docstring).
    starts : int
        Optimiser starts.

    Returns
    -------
    RationalFit
    """
    k = np.asarray(k, dtype=float)
    Q = np.asarray(Q, dtype=complex)
    order = np.argsort(k)
    k, Q = k[order], Q[order]
    if k.ndim != 1 or Q.shape[:1] != k.shape or Q.ndim != 3 or Q.shape[1] != Q.shape[2]:
        raise InputError(f"fit_rfa: Q has shape {Q.shape} for {k.size} reduced frequencies. "
                         "Fix: pass Q of shape (nk, n, n).")
    if k[0] <= 0 or np.any(np.diff(k) <= 0):
        raise InputError(f"fit_rfa: reduced frequencies {k.tolist()} must be distinct and > 0 (the "
                         "k -> 0 slope is taken from the smallest k). Fix: drop k = 0 and "
                         "duplicates from the MKAERO list.")
    if k_max is not None:
        keep = k <= k_max * (1 + 1e-12)
        k, Q = k[keep], Q[keep]
    fixed_beta = beta is not None
    beta = np.asarray(beta if fixed_beta else np.zeros(nlag), dtype=float).reshape(-1)
    fixed_pairs = pairs is not None or npair == 0
    pairs = np.asarray(pairs if pairs is not None else np.zeros((npair, 2)), dtype=float)
    pairs = pairs.reshape(-1, 2)
    nt = 3 + beta.size + 2 * pairs.shape[0]
    if 2 * k.size - 2 < nt:
        raise InputError(f"fit_rfa: {k.size} reduced frequencies (k <= {k_max}) cannot fit {nt} "
                         "coefficient matrices. Fix: use fewer lags, a larger k_max or more "
                         "MKAERO1 k values.")
    if (fixed_beta and np.any(beta <= 0)) or (fixed_pairs and np.any(pairs <= 0)):
        raise InputError("fit_rfa: lag roots beta, sigma and w must be > 0. Fix: pass positive "
                         "values (stable lags).")
    scale = np.abs(Q).max(axis=0)
    empty = scale < floor * scale.max()
    weight = 1.0 / np.maximum(scale, floor * scale.max())
    free = (0 if fixed_beta else beta.size) + (0 if fixed_pairs else 2 * pairs.shape[0])

    def unpack(x):
        b = beta if fixed_beta else np.exp(x[:beta.size])
        pr = pairs if fixed_pairs else np.exp(x[x.size - 2 * pairs.shape[0]:]).reshape(-1, 2)
        return b, pr

    def residual(x):
        res = _solve(k, Q, weight, *unpack(x))[1]
        return np.concatenate([res.real.ravel(), res.imag.ravel()])

    def strict(x):
        res = np.abs(_solve(k, Q, weight, *unpack(x))[1]).max(axis=0)
        return float(np.where(empty, 0.0, res).max())

    best = np.zeros(0)
    # small products: BLAS threads only spin on them (72 s instead of 3 s on 2 shared cores)
    with threadpool_limits(limits=1, user_api="blas"):
        best = _optimise(residual, strict, free, k, starts) if free else best
    beta, pairs = unpack(best)
    A, res = _solve(k, Q, weight, beta, pairs)
    err = np.where(empty, 0.0, np.abs(res).max(axis=0))
    overall = float(np.abs(res / weight).max() / np.abs(Q).max())
    return RationalFit(A=A, beta=beta, pairs=pairs, refc=float(refc), mach=float(mach), k=k,
                       entry_error=err, fit_error=float(err.max()), overall_error=overall)


def _optimise(residual, strict, free: int, k: np.ndarray, starts: int = STARTS) -> np.ndarray:
    """Log lag roots minimising the weighted residual (variable projection), bounded to
    [0.2 k_2, 2 k_max], from ``starts`` starts (evenly spaced, then seeded log-uniform); the one
    with the smallest strict error is returned."""
    lo, hi = np.log(0.2 * k[min(1, k.size - 1)]), np.log(2.0 * k[-1])
    rng = np.random.default_rng(0)
    trials = []
    for s in range(max(starts, 1)):
        x0 = np.linspace(lo + 0.1, hi - 0.1, free) if s == 0 else np.sort(rng.uniform(lo, hi, free))
        x = least_squares(residual, x0, bounds=(lo, hi)).x
        trials.append((strict(x), s, x))
    return min(trials)[2]


def fit_roger(gaf: xr.Dataset, mach: float, **options) -> RationalFit:
    """:func:`fit_rfa` of ``gaf.Q`` at one tabulated Mach number.

    Parameters
    ----------
    gaf : xarray.Dataset
        ``Q(mach, k, mode_i, mode_j)`` with attrs ``refc``.
    mach : float
        A tabulated Mach number.
    **options
        As :func:`fit_rfa` (nlag, npair, beta, pairs, k_max, floor, starts).

    Returns
    -------
    RationalFit
    """
    machs = np.asarray(gaf["mach"].values, dtype=float)
    j = np.flatnonzero(np.isclose(machs, mach, atol=1e-6))
    if j.size == 0:
        raise InputError(f"fit_roger: Mach {mach} is not tabulated ({machs.tolist()}). Fix: fit at "
                         "one of the GAF Mach numbers.")
    Q = np.asarray(gaf["Q"].transpose("mach", "k", "mode_i", "mode_j").values[j[0]], dtype=complex)
    return fit_rfa(gaf["k"].values, Q, refc=float(gaf.attrs["refc"]), mach=float(machs[j[0]]),
                   **options)
