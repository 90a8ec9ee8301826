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
    for r in range(R):
        lu, piv, info = zgetrf(T[r])
        if info > 0:
            lu, piv, info = zgetrf(T[r] + np.finfo(float).eps * np.abs(T[r]).max() * np.eye(n))
        u[r] = zgetrs(lu, piv, x[r])[0]
        w[r] = zgetrs(lu, piv, y[r], trans=2)[0]
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    return u, w


def pencil_system(G: np.ndarray, kc: np.ndarray, cd: np.ndarray, q: np.ndarray,
                  hc: np.ndarray | None, p: np.ndarray, M: np.ndarray, K: np.ndarray, B: np.ndarray,
                  u: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The p-k matrix T(p) of each root and the right-hand sides of its inverse-iteration step.

    T(p) = K_t + p C + p^2 M with K_t = K_hh - q (G0 + kc G1) (q = rho V^2 / 2, Q^R interpolated
    linearly in k) and C = B_hh - cd (G2 + kc G3) + hc K_hh (cd = rho cbar V / 4, Q^I/k interpolated;
    hc = g / omega for hysteretic structural damping) (MSC Nastran Aeroelastic Analysis User's Guide,
    PK method); x = T'(p) u and y = T'(p)^H w with T' = 2 M p + C (Ruhe, SIAM J. Numer. Anal. 10(4),
    1973, nonlinear inverse iteration). Every matrix product is taken on the flattened (n * n)
    matrices so the per-root scalings broadcast along rows of length n * n.

    Parameters
    ----------
    G : ndarray, shape (R, 4, n, n)
        G0, G1, G2, G3 of each root's k interval (:meth:`GafInterpolator.linearised`).
    kc, cd, q : ndarray, shape (R,)
        Clipped reduced frequency and the damping and stiffness factors of each root's flight point.
    hc : ndarray, shape (R,), or None
        Hysteretic damping g / omega per root, or None.
    p : ndarray, shape (R,), complex
        Eigenvalue estimate (shift) of each root.
    M, K, B : ndarray, shape (n, n)
        Modal mass, stiffness and viscous damping.
    u, w : ndarray, shape (R, n), complex
        Current right and left vectors.

    Returns
    -------
    T : ndarray, shape (R, n, n), complex
    x, y : ndarray, shape (R, n), complex
    """
    R, n = u.shape
    Gf = G.reshape(R, 4, n * n)
    C = Gf[:, 3] * kc[:, None]
    C += Gf[:, 2]
    C *= -cd[:, None]
    C += B.ravel()
    if hc is not None:
        C += hc[:, None] * K.ravel()
    Kt = Gf[:, 1] * kc[:, None]
    Kt += Gf[:, 0]
    Kt *= -q[:, None]
    Kt += K.ravel()
    p2 = p * p
    T = np.empty((R, n * n), dtype=complex)
    Tr, Ti = T.real, T.imag
    np.multiply(C, p.real[:, None], out=Tr)
    Tr += Kt
    Tr += p2.real[:, None] * M.ravel()
    np.multiply(C, p.imag[:, None], out=Ti)
    Ti += p2.imag[:, None] * M.ravel()
    C = C.reshape(R, n, n)
    x = 2 * p[:, None] * (u @ M.T) + real_matvec(C, u)
    y = 2 * p.conj()[:, None] * (w @ M) + real_matvec(C.transpose(0, 2, 1), w)
    return T.reshape(R, n, n), x, y


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
