"""Consistency checks of the batched p-k kernels (flutter.linalg) against dense, per-root formulas.

pencil_system, rayleigh and inverse_iteration are the hot path of flutter.pk_solver; each is checked
here on random data against the formula it implements, written out with plain dense matrices:
T(p) = K_t + p C + p^2 M with K_t = K - q (G0 + kc G1) and C = B - cd (G2 + kc G3) + hc K
(MSC Nastran PK equation, Q^R and Q^I/k linear in k on the root's interval), the two-sided Rayleigh
functional w^H T(p) u = 0 (Ruhe 1973) and one step of inverse iteration.
"""
from __future__ import annotations

import numpy as np
import pytest

from flutter.linalg import inverse_iteration, pencil_system, rayleigh

N, R = 6, 4


def _case(seed, hysteretic):
    rng = np.random.default_rng(seed)
    M = np.eye(N) + 0.1 * rng.standard_normal((N, N))
    K = np.diag(np.linspace(1.0, 30.0, N)) + 0.2 * rng.standard_normal((N, N))
    B = 0.05 * rng.standard_normal((N, N))
    G = rng.standard_normal((R, 4, N, N))
    kc, cd, q = rng.uniform(0.1, 2.0, R), rng.uniform(0.1, 1.0, R), rng.uniform(0.1, 1.0, R)
    hc = rng.uniform(0.0, 0.05, R) if hysteretic else None
    p = rng.standard_normal(R) + 1j * rng.uniform(0.5, 5.0, R)
    u = rng.standard_normal((R, N)) + 1j * rng.standard_normal((R, N))
    w = rng.standard_normal((R, N)) + 1j * rng.standard_normal((R, N))
    return M, K, B, G, kc, cd, q, hc, p, u, w


def _dense(M, K, B, G, kc, cd, q, hc, r):
    """C and K_t of root r, written out."""
    C = B - cd[r] * (G[r, 2] + kc[r] * G[r, 3]) + (hc[r] * K if hc is not None else 0.0)
    Kt = K - q[r] * (G[r, 0] + kc[r] * G[r, 1])
    return C, Kt


@pytest.mark.parametrize("hysteretic", [False, True])
def test_pencil_system_matches_dense_formula(hysteretic):
    M, K, B, G, kc, cd, q, hc, p, u, w = _case(1, hysteretic)
    T, x, y = pencil_system(G, kc, cd, q, hc, p, M, np.stack([K.ravel(), B.ravel(), M.ravel()]),
                            u, w)
    for r in range(R):
        C, Kt = _dense(M, K, B, G, kc, cd, q, hc, r)
        T_ref = Kt + p[r] * C + p[r] ** 2 * M
        Tp = 2 * p[r] * M + C
        scale = np.abs(T_ref).max()
        assert np.abs(T[r] - T_ref).max() <= 1e-13 * scale
        assert np.abs(x[r] - Tp @ u[r]).max() <= 1e-13 * np.abs(Tp @ u[r]).max()
        assert np.abs(y[r] - Tp.conj().T @ w[r]).max() <= 1e-13 * np.abs(Tp.conj().T @ w[r]).max()


@pytest.mark.parametrize("hysteretic", [False, True])
def test_rayleigh_root_and_k_derivative(hysteretic):
    M, K, B, G, kc, cd, q, hc, p, u, w = _case(2, hysteretic)
    MKB = np.concatenate([M.T, K.T, B.T], axis=1).astype(complex)
    sloped = np.ones(R, dtype=bool)
    pn, dpdk = rayleigh(G, kc, sloped, cd, q, hc, MKB, u, w, p)
    h = 1e-6
    up, _ = rayleigh(G, kc + h, sloped, cd, q, hc, MKB, u, w, pn)
    dn, _ = rayleigh(G, kc - h, sloped, cd, q, hc, MKB, u, w, pn)
    for r in range(R):
        C, Kt = _dense(M, K, B, G, kc, cd, q, hc, r)
        a = [w[r].conj() @ A @ u[r] for A in (M, C, Kt)]
        roots = np.roots(a)
        # the root of the quadratic nearest the estimate, to rounding
        assert abs(pn[r] - roots[np.argmin(np.abs(roots - p[r]))]) <= 1e-10 * abs(pn[r])
        # implicit-function derivative against a central difference in k (T is linear in k)
        fd = (up[r] - dn[r]) / (2 * h)
        assert abs(dpdk[r] - fd) <= 1e-6 * abs(fd)
    # held outside the table: no k-dependence
    _, flat = rayleigh(G, kc, np.zeros(R, dtype=bool), cd, q, hc, MKB, u, w, p)
    assert np.all(flat == 0)


def test_inverse_iteration_converges_to_the_eigenvector():
    """Shifted 1e-7 off an eigenvalue of the pencil, from a 1 % perturbed eigenvector and a random
    left vector, one step leaves residuals of order the shift error."""
    M, K, B, G, kc, cd, q, hc, _, _, _ = _case(3, False)
    for r in range(R):
        C, Kt = _dense(M, K, B, G, kc, cd, q, None, r)
        Minv = np.linalg.inv(M)
        A = np.block([[np.zeros((N, N)), np.eye(N)], [-Minv @ Kt, -Minv @ C]])
        lam, X = np.linalg.eig(A)
        j = int(np.argmax(lam.imag))
        lam_j, v = lam[j], X[:N, j]
        sigma = lam_j * (1 + 1e-7)
        T = (Kt + sigma * C + sigma ** 2 * M)[None]
        rng = np.random.default_rng(r)
        u0 = v + 1e-2 * (rng.standard_normal(N) + 1j * rng.standard_normal(N))
        w0 = rng.standard_normal(N) + 1j * rng.standard_normal(N)
        Tp = 2 * sigma * M + C
        un, wn = inverse_iteration(T, (Tp @ u0)[None], (Tp.conj().T @ w0)[None])
        assert abs(np.linalg.norm(un[0]) - 1) < 1e-12 and abs(np.linalg.norm(wn[0]) - 1) < 1e-12
        T_lam = Kt + lam_j * C + lam_j ** 2 * M
        scale = np.abs(T_lam).max()
        # residuals of order the 1e-7 shift error (measured: right <= 6e-8, left <= 1e-6)
        assert np.linalg.norm(T_lam @ un[0]) <= 1e-6 * scale
        assert np.linalg.norm(wn[0].conj() @ T_lam) <= 1e-5 * scale
