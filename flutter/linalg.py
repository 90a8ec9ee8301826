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
    return unit_rows(u), unit_rows(w)


def unit_rows(u: np.ndarray) -> np.ndarray:
    """Rows of ``u`` (R, n) scaled to unit 2-norm (a new array)."""
    return u / np.sqrt(np.einsum("ri,ri->r", u, u.conj()).real)[:, None]


def pencil_system(G: np.ndarray, kc: np.ndarray, cd: np.ndarray, q: np.ndarray,
                  hc: np.ndarray | None, p: np.ndarray, M: np.ndarray, KBM: np.ndarray,
                  u: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The p-k matrix T(p) of each root and the right-hand sides of its inverse-iteration step.

    T(p) = K_t + p C + p^2 M with K_t = K_hh - q (G0 + kc G1) (q = rho V^2 / 2, Q^R interpolated
    linearly in k) and C = B_hh - cd (G2 + kc G3) + hc K_hh (cd = rho cbar V / 4, Q^I/k interpolated;
    hc = g / omega for hysteretic structural damping) (MSC Nastran Aeroelastic Analysis User's Guide,
    PK method); x = T'(p) u and y = T'(p)^H w with T' = 2 M p + C (Ruhe, SIAM J. Numer. Anal. 10(4),
    1973, nonlinear inverse iteration). Re T, Im T and C are each one weighted sum of the root's
    G0..G3 (einsum) plus one of K, B, M (gemm), on the flattened (n * n) matrices.

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
    M : ndarray, shape (n, n)
        Modal mass.
    KBM : ndarray, shape (3, n * n)
        Modal stiffness, viscous damping and mass, flattened and stacked.
    u, w : ndarray, shape (R, n), complex
        Current right and left vectors.

    Returns
    -------
    T : ndarray, shape (R, n, n), complex
    x, y : ndarray, shape (R, n), complex
    """
    R, n = u.shape
    Gf = G.reshape(R, 4, n * n)
    p2 = p * p
    # each matrix as a weighted sum of G0..G3 (one einsum) and of K, B, M (one gemm)
    cC = np.stack([-cd, -cd * kc], axis=1)
    C = np.einsum("rj,rjk->rk", cC, Gf[:, 2:])
    C += KBM[1]
    cT = np.empty((R, 4))                   # Re T on G0..G3; Im T needs G2, G3 only
    cT[:, 0] = -q
    cT[:, 1] = -q * kc
    cT[:, 2:] = p.real[:, None] * cC
    cK = np.zeros((2, R, 3))                # Re T and Im T on K, B, M
    cK[0, :, 0] = 1.0
    cK[0, :, 1], cK[0, :, 2] = p.real, p2.real
    cK[1, :, 1], cK[1, :, 2] = p.imag, p2.imag
    if hc is not None:
        C += hc[:, None] * KBM[0]
        cK[0, :, 0] += p.real * hc
        cK[1, :, 0] += p.imag * hc
    T = np.empty((R, n * n), dtype=complex)
    np.add(np.einsum("rj,rjk->rk", cT, Gf), cK[0] @ KBM, out=T.real)
    np.add(np.einsum("rj,rjk->rk", p.imag[:, None] * cC, Gf[:, 2:]), cK[1] @ KBM, out=T.imag)
    C = C.reshape(R, n, n)
    x = 2 * p[:, None] * (u @ M.T) + real_matvec(C, u)
    y = 2 * p.conj()[:, None] * (w @ M) + real_matvec(C.transpose(0, 2, 1), w)
    return T.reshape(R, n, n), x, y


def rayleigh(G: np.ndarray, kc: np.ndarray, sloped: np.ndarray, cd: np.ndarray, q: np.ndarray,
             hc: np.ndarray | None, MKB: np.ndarray, u: np.ndarray, w: np.ndarray,
             p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two-sided Rayleigh functional of each root at its k, and its k-derivative.

    The root of w^H T(p, k) u = a2 p^2 + a1 p + a0 = 0 nearest ``p`` (Ruhe, SIAM J. Numer. Anal.
    10(4), 1973), with a2 = w^H M u, a1 = w^H C u, a0 = w^H K_t u (C and K_t as in
    :func:`pencil_system`), and dp/dk = -w^H (p dC/dk + dK_t/dk) u / w^H (2 M p + C) u (implicit
    function theorem; zero where the interpolant is held constant in k). All the bilinear forms
    come from two batched products: the four G_j u and M u, K u, B u.

    Parameters
    ----------
    G : ndarray, shape (R, 4, n, n)
    kc, cd, q : ndarray, shape (R,)
    sloped : ndarray of bool, shape (R,)
        False where k is held outside the table (d/dk = 0).
    hc : ndarray, shape (R,), or None
    MKB : ndarray, shape (n, 3 n), complex
        [M^T, K^T, B^T] side by side.
    u, w : ndarray, shape (R, n), complex
    p : ndarray, shape (R,), complex
        Current estimates (the nearer root of the quadratic is taken).

    Returns
    -------
    pn, dpdk : ndarray, shape (R,), complex
        Rayleigh functional root and its k-derivative (0 where not finite).
    """
    R, n = u.shape
    wc = w.conj()
    g = np.einsum("rji,ri->rj", real_matvec(G.reshape(R, 4 * n, n), u).reshape(R, 4, n), wc)
    s = np.einsum("rji,ri->rj", (u @ MKB).reshape(R, 3, n), wc)   # w^H M u, w^H K u, w^H B u
    a2 = s[:, 0]
    a0 = s[:, 1] - q * (g[:, 0] + kc * g[:, 1])   # w^H (K_hh - q Q^R) u
    a1 = s[:, 2] - cd * (g[:, 2] + kc * g[:, 3])  # w^H (B_hh - rho b V Q^I/(2k)) u
    if hc is not None:
        a1 = a1 + hc * s[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        disc = np.sqrt(a1 * a1 - 4 * a2 * a0 + 0j)
        r1, r2 = (-a1 + disc) / (2 * a2), (-a1 - disc) / (2 * a2)
        pn = np.where(np.abs(r1 - p) <= np.abs(r2 - p), r1, r2)
        dT = np.where(sloped, -pn * cd * g[:, 3] - q * g[:, 1], 0.0)  # w^H (p dC/dk + dK_t/dk) u
        dpdk = -dT / (2 * a2 * pn + a1)
    return pn, np.where(np.isfinite(dpdk), dpdk, 0.0)


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
