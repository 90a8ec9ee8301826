"""Flutter and divergence crossings: detection on a sweep and refinement between two points.

A crossing is a change of the damping g of one tracked root from negative to above a small tolerance
(DESIGN.md section 3): a root whose |g| never leaves the band |g| <= ``g_tol`` (~1e-6) never crosses,
so numerically neutral roots (|g| ~ 1e-15) are never reported. A crossing of an oscillatory root is
``"flutter"``; of a zero-frequency (real) root, ``"divergence"``.

Rigid-body drift roots. A free aircraft without gravity has exact zero eigenvalues: altitude and
flight-path angle (and, laterally, side displacement and heading) change no aerodynamic force. The
GAF tables hold them only to their small-k accuracy, so each double zero splits into a +-sqrt pair
(Wilkinson: a perturbed Jordan block) whose sign is rounding: on Nastran's bah_plane QHH a near-zero
root of ours turns from g = -1e-5 to +9e-4 at 363 m/s at |p| b / V = 6e-5, and Nastran's own point 1
is a real root of +9.3e-4 rad/s at 30 m/s. A root that starts as a rigid-body mode below the
tables' resolution, |p| b / V < k_min (the smallest tabulated reduced frequency), is such a drift
root (:func:`drift_roots`); while it stays below that resolution its sign changes are not crossings
(:func:`resolved_damping`). Once it leaves it (a real static instability, or a drift root caught by
another mode), its crossings count as any other root's.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

G_TOL = 1e-6


@dataclass(frozen=True)
class Crossing:
    """One crossing of g through zero.

    Attributes
    ----------
    root : int
        Root number (1-based).
    index : int
        Index of the last sweep point before the crossing.
    t : float
        Fraction of the way from point ``index`` to ``index + 1`` (0..1).
    velocity, density, mach, frequency : float
        Flight point and frequency (Hz) at the crossing.
    kind : str
        ``"flutter"`` or ``"divergence"``.
    converged : bool
        Both bracketing points (and the refinement) converged.
    refined : bool
        True if located by root-finding on the solver, False if linearly interpolated.
    """

    root: int
    index: int
    t: float
    velocity: float
    density: float
    mach: float
    frequency: float
    kind: str
    converged: bool
    refined: bool

    def as_dict(self) -> dict:
        """The summary.json entry (DESIGN.md section 6), plus the convergence flag."""
        return {"mach": self.mach, "density": self.density, "velocity": self.velocity,
                "frequency": self.frequency, "root": self.root, "kind": self.kind,
                "converged": self.converged}


def root_damping(p: np.ndarray, velocity, b: float, real: np.ndarray) -> np.ndarray:
    """Damping g of roots (DESIGN.md section 3): 2 Re p / Im p, and Nastran's g = p cbar /
    (V ln 2) = 2 p b / (V ln 2) for the roots flagged ``real`` (the F06's value for KFREQ = 0).

    Parameters
    ----------
    p : ndarray, complex
        Eigenvalues.
    velocity : float or ndarray, broadcast against ``p``
        Flight velocity of each root.
    b : float
        Reference semi-chord (REFC / 2).
    real : ndarray of bool, shape as ``p``
        Roots that are real (each solver's own test of Im p = 0).

    Returns
    -------
    ndarray, shape as ``p``
    """
    p = np.asarray(p)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(real, p.real * 2 * b / (np.asarray(velocity) * np.log(2.0)),
                        2.0 * p.real / np.where(real, 1.0, p.imag))


def crossing_at(root: int, index: int, t: float, start: tuple, end: tuple, p: complex, *,
                real: bool, converged: bool, refined: bool) -> Crossing:
    """The crossing of a root a fraction ``t`` of the way between two flight points.

    Parameters
    ----------
    root, index : int
        0-based root and the sweep point before the crossing.
    t : float
        Fraction of the way from ``start`` to ``end`` (0..1).
    start, end : tuple of float
        (V, rho, M) of points ``index`` and ``index + 1``; the crossing's flight point is their
        linear interpolation.
    p : complex
        The root's eigenvalue at the crossing.
    real : bool
        The root is real there: a divergence (frequency 0); else flutter at |Im p| / 2 pi.
    converged, refined : bool
        As :class:`Crossing`.

    Returns
    -------
    Crossing
    """
    V, rho, M = (a + t * (b - a) for a, b in zip(start, end))
    return Crossing(root=root + 1, index=int(index), t=float(t), velocity=float(V),
                    density=float(rho), mach=float(M),
                    frequency=0.0 if real else float(abs(p.imag) / (2 * np.pi)),
                    kind="divergence" if real else "flutter", converged=bool(converged),
                    refined=bool(refined))


def find_brackets(damping: np.ndarray, g_tol: float = G_TOL) -> list[tuple[int, int]]:
    """Sweep intervals where a root's damping goes from below 0 to above ``g_tol``.

    Parameters
    ----------
    damping : ndarray, shape (npts, nroot)
        Damping g of each tracked root along the sweep.
    g_tol : float
        Band of numerically neutral damping.

    Returns
    -------
    list of (root_index, point_index)
        0-based root and the point before each crossing, ordered by point then root.
    """
    g = np.asarray(damping, dtype=float)
    up = (g[:-1] < 0) & (g[1:] > g_tol)
    i, r = np.nonzero(up)
    return [(int(rr), int(ii)) for ii, rr in sorted(zip(i, r))]


def drift_roots(p: np.ndarray, velocity: np.ndarray, b: float, k_min: np.ndarray,
                rigid: np.ndarray) -> np.ndarray:
    """Rigid-body drift roots and where they are below the GAF tables' resolution (module docstring).

    Parameters
    ----------
    p : ndarray, shape (npts, nroot), complex
        Eigenvalues of the tracked roots along a sweep.
    velocity : ndarray, shape (npts,)
        Flight velocity of each point (or, k method, of each root: shape (npts, nroot)).
    b : float
        Reference semi-chord (REFC / 2).
    k_min : ndarray, shape (npts,)
        Smallest tabulated reduced frequency at each point's Mach number (0: no table).
    rigid : ndarray of bool, shape (nroot,)
        Roots that start from a rigid-body mode.

    Returns
    -------
    ndarray of bool, shape (npts, nroot)
        True where a drift root (rigid, below the resolution at the first point) is below the
        resolution, |p| b / V < k_min.
    """
    V = np.asarray(velocity, dtype=float)
    V = V[:, None] if V.ndim == 1 else V
    below = np.abs(p) * b / V < np.asarray(k_min, dtype=float)[:, None]
    return below & (np.asarray(rigid, dtype=bool) & below[0])[None, :]


def resolved_damping(damping: np.ndarray, drift: np.ndarray) -> np.ndarray:
    """Damping with the points of unresolved drift roots set to NaN (no crossing there).

    Parameters
    ----------
    damping : ndarray, shape (npts, nroot)
    drift : ndarray of bool, shape (npts, nroot)
        From :func:`drift_roots`.

    Returns
    -------
    ndarray, shape (npts, nroot)
        A new array for :func:`find_brackets` (NaN compares false, so no bracket touches them).
    """
    return np.where(drift, np.nan, np.asarray(damping, dtype=float))


def interpolate_zero(g0: float, g1: float) -> float:
    """Fraction t in [0, 1] where the line through (0, g0) and (1, g1) is zero."""
    return float(g0 / (g0 - g1))


def illinois(fun: Callable[[float], float], g0: float, g1: float, *, xtol: float = 1e-7,
             max_iter: int = 40) -> tuple[float, bool]:
    """Zero of ``fun`` on [0, 1] by the Illinois (modified regula falsi) method.

    Parameters
    ----------
    fun : callable
        t -> g, with fun(0) = g0 < 0 < g1 = fun(1).
    g0, g1 : float
        Values at the ends.
    xtol : float
        Tolerance on t.

    Returns
    -------
    t : float
    ok : bool
        Converged within ``max_iter``.
    """
    a, b, fa, fb = 0.0, 1.0, g0, g1
    side = 0
    t_prev = None
    scale = max(abs(g0), abs(g1))
    for _ in range(max_iter):
        t = (a * fb - b * fa) / (fb - fa)
        ft = fun(t)
        if not np.isfinite(ft):
            return t, False
        if abs(ft) <= 1e-12 * scale or (t_prev is not None and abs(t - t_prev) < xtol):
            return t, True
        t_prev = t
        if ft * fb > 0:
            b, fb = t, ft
            if side == -1:
                fa *= 0.5
            side = -1
        else:
            a, fa = t, ft
            if side == 1:
                fb *= 0.5
            side = 1
    return t, False
