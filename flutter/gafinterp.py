"""Interpolation of generalized aerodynamic forces Q_hh(M, k) at the reduced frequency of a root.

The p-k equation needs Q_hh at each root's own reduced frequency k = omega * b / V (b = REFC / 2).
The damping term uses Q^I / k (Nastran Aeroelastic Analysis User's Guide, PK method, eq. for the
aerodynamic damping matrix ``-(1/4) rho cbar V Q^I_hh / k``); Q^I / k is smooth down to k = 0 and is
interpolated directly, so zero-frequency (rigid-body, divergence) roots are well defined.

Below the smallest tabulated k, Q^R and Q^I / k are continued as even functions of k through the two
smallest tabulated k, Q^R(k) = Q^R_0 + c_R k^2 and Q^I(k)/k = D_0 + c_D k^2: the GAFs of harmonic
motion satisfy Q(-ik) = conj(Q(ik)), so both are even in k and their small-k form is a value at k = 0
plus O(k^2) (the apparent-mass term of Q^R is -k^2 times an apparent mass). Holding them at the
smallest tabulated k instead keeps that term, k_min^2 times the apparent mass, as a spurious
stiffness on every rigid-body mode: it splits the exact double zero of altitude and flight-path angle
of a free aircraft into a +-sqrt pair (Nastran's bah_plane QHH at 30 m/s: 0.0055 rad/s, slightly
unstable, held; 0.0003 rad/s and stable, continued).
"""
from __future__ import annotations

from typing import Callable

import numpy as np
import xarray as xr
from scipy.interpolate import CubicSpline

from structures.common.errors import InputError

INTERPOLATIONS = ("linear", "cubic")
_K_EPS = 1e-6  # k used for Q^I/k at k = 0 when Q is given as a callable


class GafInterpolator:
    """Q^R(k) and Q^I(k)/k at one Mach number, for arrays of k.

    Parameters
    ----------
    gaf : xarray.Dataset or callable
        Dataset with ``Q(mach, k, mode_i, mode_j)`` (complex; DESIGN.md section 6), or a callable
        ``gaf(mach, k) -> Q`` with k of shape (nk,) returning shape (nk, n, n).
    mach : float
        Mach number. A Dataset is used at that tabulated Mach, or linearly interpolated between the
        two tabulated Mach numbers around it.
    interpolation : {"linear", "cubic"}
        Interpolation in k (Nastran's PK uses linear interpolation of the tabulated matrices).
    """

    def __init__(self, gaf: xr.Dataset | Callable, mach: float, interpolation: str = "linear"):
        if interpolation not in INTERPOLATIONS:
            raise InputError(f"GafInterpolator: unknown interpolation {interpolation!r}. "
                             f"Fix: use one of {INTERPOLATIONS}.")
        self.mach = float(mach)
        self.callable = None
        if callable(gaf) and not isinstance(gaf, xr.Dataset):
            self.callable = gaf
            self.k_min, self.k_max = 0.0, np.inf
            self.n = np.asarray(gaf(self.mach, np.array([0.1]))).shape[-1]
            return
        Q = _q_at_mach(gaf, self.mach)  # (nk, n, n)
        k = np.asarray(gaf["k"].values, dtype=float)
        order = np.argsort(k)
        k, Q = k[order], Q[order]
        if np.any(np.diff(k) <= 0) or k[0] <= 0:
            raise InputError(f"GAF Dataset: reduced frequencies {k.tolist()} must be distinct and > 0 "
                             "(the damping term divides by k). Fix: drop k = 0 and duplicates from "
                             "the MKAERO list.")
        self.k_grid = k
        self.k_min, self.k_max = float(k[0]), float(k[-1])
        self.n = Q.shape[-1]
        self._QR = Q.real
        self._D = Q.imag / k[:, None, None]
        # even continuation below the table: Q^R = QR0 + cR k^2, Q^I/k = D0 + cD k^2 (module docstring)
        if k.size > 1:
            dk2 = k[1] ** 2 - k[0] ** 2
            self._cR, self._cD = (self._QR[1] - self._QR[0]) / dk2, (self._D[1] - self._D[0]) / dk2
        else:
            self._cR = self._cD = np.zeros_like(self._QR[0])
        self._QR0 = self._QR[0] - self._cR * k[0] ** 2
        self._D00 = self._D[0] - self._cD * k[0] ** 2
        self.interpolation = interpolation
        if interpolation == "cubic":
            if k.size < 3:
                raise InputError("GAF Dataset: cubic interpolation in k needs at least 3 k values. "
                                 "Fix: use interpolation='linear' or add MKAERO k values.")
            self._sR = CubicSpline(k, self._QR, axis=0)
            self._sD = CubicSpline(k, self._D, axis=0)
            self._dR, self._dD = self._sR.derivative(), self._sD.derivative()
        else:
            # per-interval line coefficients, Q(k) = c0[i] + c1[i] k on [k_i, k_i+1]: one gather per
            # coefficient for a whole batch of roots
            h = np.diff(k)[:, None, None]
            self._R1 = np.diff(self._QR, axis=0) / h
            self._D1 = np.diff(self._D, axis=0) / h
            self._R0 = self._QR[:-1] - self._R1 * k[:-1, None, None]
            self._D0 = self._D[:-1] - self._D1 * k[:-1, None, None]
            self._table = np.ascontiguousarray(np.stack([self._R0, self._R1, self._D0, self._D1], 1))

    def __call__(self, k: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Q^R, Q^I/k and an out-of-range flag at reduced frequencies ``k``.

        Parameters
        ----------
        k : ndarray, shape (r,)
            Reduced frequencies k = omega * b / V (>= 0).

        Returns
        -------
        QR, D : ndarray, shape (r, n, n)
            Real part of Q and imaginary part divided by k.
        outside : ndarray of bool, shape (r,)
            True where k lies above the tabulated range (not covered by the GAFs; Q is held at the
            largest tabulated k there). Below the smallest tabulated k, Q^R and Q^I/k are continued
            as even functions of k (module docstring) and not flagged.
        """
        QR, D, _, _, outside = self.with_slopes(k, slopes=False)
        return QR, D, outside

    def with_slopes(self, k: np.ndarray, slopes: bool = True):
        """Q^R, Q^I/k, their k-derivatives and the out-of-range flag at reduced frequencies ``k``.

        Parameters
        ----------
        k : ndarray, shape (r,)
            Reduced frequencies (>= 0).
        slopes : bool
            Compute the derivatives (else they are returned as None).

        Returns
        -------
        QR, D : ndarray, shape (r, n, n)
            As :meth:`__call__`.
        dQR, dD : ndarray, shape (r, n, n) or None
            d Q^R / dk and d (Q^I/k) / dk of the interpolant (zero above the table; one-sided
            finite difference, step 1e-6 k, for a callable).
        outside : ndarray of bool, shape (r,)
        """
        k = np.asarray(k, dtype=float)
        if self.callable is not None:
            kk = np.maximum(k, _K_EPS)
            Q = np.asarray(self.callable(self.mach, kk), dtype=complex)
            QR, D = Q.real, Q.imag / kk[:, None, None]
            dQR = dD = None
            if slopes:
                h = 1e-6 * kk
                Qh = np.asarray(self.callable(self.mach, kk + h), dtype=complex)
                dQR = (Qh.real - QR) / h[:, None, None]
                dD = (Qh.imag / (kk + h)[:, None, None] - D) / h[:, None, None]
            return QR, D, dQR, dD, np.zeros(k.shape, dtype=bool)
        tol = 1e-9
        outside = k > self.k_max * (1 + tol)
        kc = np.clip(k, self.k_min, self.k_max)
        if self.interpolation == "cubic":
            QR, D = self._sR(kc), self._sD(kc)
            dQR, dD = (self._dR(kc), self._dD(kc)) if slopes else (None, None)
        else:
            i = np.clip(np.searchsorted(self.k_grid, kc) - 1, 0, self.k_grid.size - 2)
            dQR, dD = self._R1[i], self._D1[i]
            kb = kc[:, None, None]
            QR = self._R0[i] + dQR * kb   # linear interpolation in k, as Nastran's PK
            D = self._D0[i] + dD * kb
        below = k < self.k_min
        if below.any():
            QR, D, eR, eD = self._even(k, below, QR, D)
            if slopes:
                dQR, dD = np.where(below[:, None, None], eR, dQR), np.where(below[:, None, None], eD, dD)
        if not slopes:
            return QR, D, None, None, outside
        if outside.any():
            dQR, dD = np.where(outside[:, None, None], 0.0, dQR), np.where(outside[:, None, None], 0.0, dD)
        return QR, D, dQR, dD, outside

    def _even(self, k: np.ndarray, below: np.ndarray, QR: np.ndarray, D: np.ndarray):
        """Q^R, Q^I/k and their k-slopes with the rows ``below`` the table replaced by the even
        continuation Q^R_0 + c_R k^2, D_0 + c_D k^2 (module docstring); new arrays."""
        kb = k[:, None, None]
        sel = below[:, None, None]
        QR = np.where(sel, self._QR0 + self._cR * kb ** 2, QR)
        D = np.where(sel, self._D00 + self._cD * kb ** 2, D)
        return QR, D, 2 * self._cR * kb, 2 * self._cD * kb

    def linearised(self, k: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The interpolant as a line in k about each k: Q^R = G0 + kc G1 and Q^I/k = G2 + kc G3.

        For linear interpolation G holds the coefficients of each root's k interval (one gather
        from a table, no arithmetic); otherwise the values and slopes at k.

        Parameters
        ----------
        k : ndarray, shape (r,)

        Returns
        -------
        G : ndarray, shape (r, 4, n, n)
            G0, G1 = d Q^R / dk, G2, G3 = d (Q^I/k) / dk, where ``sloped``.
        kc : ndarray, shape (r,)
            k clipped to the table (where the interpolant is held constant outside).
        sloped : ndarray of bool, shape (r,)
            False where k lies outside the table (the k-derivatives there are zero, not G1, G3).
        outside : ndarray of bool, shape (r,)
            As :meth:`__call__`.
        """
        k = np.asarray(k, dtype=float)
        if self.callable is None and self.interpolation == "linear":
            outside = k > self.k_max * (1 + 1e-9)
            below = k < self.k_min
            kc = np.minimum(np.maximum(k, self.k_min), self.k_max)  # (np.clip: same, slower)
            i = np.minimum(np.maximum(np.searchsorted(self.k_grid, kc) - 1, 0), self.k_grid.size - 2)
            G = self._table[i]
            if below.any():  # the even continuation as a line about each root's own k
                kb = np.where(below, k, 0.0)
                QR, D, dQR, dD = self._even(kb, np.ones(k.size, dtype=bool), G[:, 0], G[:, 2])
                line = np.stack([QR - kb[:, None, None] * dQR, dQR, D - kb[:, None, None] * dD, dD], 1)
                G = np.where(below[:, None, None, None], line, G)
                kc = np.where(below, k, kc)
            return G, kc, ~outside, outside
        QR, D, dQR, dD, outside = self.with_slopes(k)
        kb = np.minimum(k, self.k_max)[:, None, None] if self.callable is None else k[:, None, None]
        G = np.stack([QR - kb * dQR, dQR, D - kb * dD, dD], axis=1)
        return G, kb[:, 0, 0], ~outside, outside


def _q_at_mach(gaf: xr.Dataset, mach: float) -> np.ndarray:
    """Q(k, i, j) of a GAF Dataset at ``mach`` (exact or linear between tabulated Mach numbers)."""
    if "Q" not in gaf:
        raise InputError("GAF Dataset has no variable 'Q'. Fix: pass the Dataset written by aero.gaf "
                         "(Q(mach, k, mode_i, mode_j)).")
    Q = gaf["Q"].transpose("mach", "k", "mode_i", "mode_j")
    values = np.asarray(Q.values)
    if not np.all(np.isfinite(values)):
        bad = np.argwhere(~np.isfinite(values))[0]
        raise InputError(f"GAF Dataset: Q_hh contains NaN/inf (first at mach={float(Q.mach[bad[0]])}, "
                         f"k={float(Q.k[bad[1]])}, mode_i={int(Q.mode_i[bad[2]])}, "
                         f"mode_j={int(Q.mode_j[bad[3]])}). Fix: recompute the GAFs for that "
                         "Mach/k (check the spline and the AIC solve).")
    machs = np.asarray(Q["mach"].values, dtype=float)
    j = np.flatnonzero(np.isclose(machs, mach, rtol=0, atol=1e-6))
    if j.size:
        return values[j[0]].astype(complex)
    if not machs.min() < mach < machs.max():
        raise InputError(f"GAF Dataset: Mach {mach} is outside the tabulated Mach numbers "
                         f"{sorted(machs.tolist())}. Fix: add the Mach number to MKAERO1/MKAERO2.")
    order = np.argsort(machs)
    m = machs[order]
    i = np.searchsorted(m, mach) - 1
    t = (mach - m[i]) / (m[i + 1] - m[i])
    return ((1 - t) * values[order[i]] + t * values[order[i + 1]]).astype(complex)
