"""Small batched linear-algebra kernels of the p-k continuation (flutter.pk)."""
from __future__ import annotations

import numpy as np
from scipy.linalg.lapack import zgetrf, zgetrs


def inverse_iteration(T: np.ndarray, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One right and one left inverse-iteration step per root with a single LU each.

    Solves T_r u_r = x_r and T_r^H w_r = y_r (LAPACK zgetrf / zgetrs, trans='C') and normalises.
    A singular T_r (an exactly converged root) is shifted by eps * max|T_r| so the null vector is
    still returned.

    Parameters
    ----------
    T : ndarray, shape (R, n, n)
    x, y : ndarray, shape (R, n)

    Returns
    -------
    u, w : ndarray, shape (R, n), unit 2-norm
    """
    R, n, _ = T.shape
    u = np.empty((R, n), dtype=complex)
    w = np.empty((R, n), dtype=complex)
    eye = np.eye(n)
    for r in range(R):
        lu, piv, info = zgetrf(T[r])
        if info > 0:
            lu, piv, info = zgetrf(T[r] + np.finfo(float).eps * np.abs(T[r]).max() * eye)
        u[r] = zgetrs(lu, piv, x[r])[0]
        w[r] = zgetrs(lu, piv, y[r], trans=2)[0]
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    return u, w


def real_matvec(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Batched products of real matrices with complex vectors, A_r x_r.

    One real matmul on the (re, im) pairs of x, so A is never copied to complex.

    Parameters
    ----------
    A : ndarray, shape (R, n, n), real
    x : ndarray, shape (R, n), complex

    Returns
    -------
    ndarray, shape (R, n), complex
    """
    x = np.ascontiguousarray(x, dtype=complex)
    return np.ascontiguousarray(A @ x.view(float).reshape(*x.shape, 2)).view(complex)[..., 0]


def path_length(frm: tuple, to: tuple) -> float:
    """Length of a step between flight points (relative V and rho changes, absolute Mach change)."""
    (V0, r0, m0), (V1, r1, m1) = frm, to
    return float(np.sqrt(((V1 - V0) / V0) ** 2 + ((r1 - r0) / r0) ** 2 + (m1 - m0) ** 2))
