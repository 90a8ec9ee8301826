"""Block shift-invert Lanczos for the lowest eigenpairs of K phi = lambda M phi.

The operator S = (K - sigma M)^-1 M is self-adjoint in the M inner product, and its largest
eigenvalues theta = 1 / (lambda - sigma) are the wanted (lowest) modes. The Krylov basis is built a
block of ``p`` vectors at a time: one multi-right-hand-side solve per step (a sparse factor is read
once for all ``p`` vectors) and orthogonalisation by matrix-matrix products, where single-vector
Lanczos (ARPACK) spends most of its time in memory-bound matrix-vector products against the basis.

The start block is S applied to random vectors, so that the basis lies in the range of S, where
the M semi-norm (M is singular when some DOFs carry no mass) is a norm and the Ritz vectors carry
no spurious massless components (Ericsson & Ruhe, Math. Comp. 35 (1980) 1251-1268). Each new
block S V_j is M-orthogonalised against the whole basis by classical Gram-Schmidt done
twice; the projection coefficients are exactly the entries of T = V^T M S V (symmetric, so its
upper block triangle suffices), and Rayleigh-Ritz on T gives the Ritz pairs (theta, V y). With
S V = V T + W E^T (W the orthogonalised remainder of the last block), the residual of a Ritz pair is
W y_last, of M-norm sqrt(y_last^T W^T M W y_last). When the basis is full, it restarts thickly from
the best Ritz vectors (T becomes diag(theta) there, and the coefficients of later blocks against them
are again projections). References: Golub & Van Loan, Matrix Computations, 4th ed., sec. 10.3.6
(block Lanczos); Grimes, Lewis & Simon, SIAM J. Matrix Anal. Appl. 15 (1994) 228-272 (shifted block
Lanczos for the generalized problem); Stewart, SIAM J. Matrix Anal. Appl. 23 (2001) 601-614
(Krylov-Schur thick restart).
"""
from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.sparse as sp

BLOCK = 12
DEFLATION = 1e-10          # a new direction shorter than this (relative) lies in the basis already
MAX_RESTARTS = 30


def block_lanczos(solve: Callable[[np.ndarray], np.ndarray], m: sp.spmatrix, nmodes: int, *,
                  block: int = BLOCK, tol: float = 1e-9, max_vectors: int | None = None,
                  seed: int = 0) -> tuple[np.ndarray, np.ndarray, bool]:
    """Largest ``nmodes`` eigenpairs of S = A^-1 M, self-adjoint in the M inner product.

    Parameters
    ----------
    solve : callable, b (n, p) -> A^-1 b (n, p), with A = K - sigma M positive definite.
    m : sparse (n, n) symmetric positive semi-definite mass matrix.
    nmodes : int, number of wanted eigenpairs (nmodes < n).
    block : int, vectors per block p.
    tol : float, a Ritz pair is converged when ||S x - theta x||_M <= tol * theta.
    max_vectors : int, optional, basis size before a thick restart (default
        max(5 nmodes, nmodes + 12 p), at most n).
    seed : int, seed of the random start block (results do not depend on it beyond ``tol``).

    Returns
    -------
    theta : (nmodes,) descending.
    x : (n, nmodes) M-orthonormal Ritz vectors.
    converged : bool, False when MAX_RESTARTS restarts did not converge every pair.
    """
    n = m.shape[0]
    p = min(block, n - nmodes) if n > nmodes else 1
    cap = min(n, max_vectors or max(5 * nmodes, nmodes + 12 * p))
    keep = min(nmodes + p, cap - 2 * p) if cap >= nmodes + 3 * p else nmodes
    rng = np.random.default_rng(seed)
    basis = np.empty((n, cap), order="F")
    t = np.zeros((cap, cap))
    k = 0
    start = solve(m @ rng.standard_normal((n, p)))          # in range(S), where M-norm is a norm
    gram = start.T @ (m @ start)
    v = _orthonormal_block(start, m, basis[:, :0], rng, float(np.max(np.diag(gram))), gram)
    for restart in range(MAX_RESTARTS + 1):
        while True:
            basis[:, k:k + p] = v
            k += p
            w = solve(m @ v)
            scale = float(np.max(np.einsum("ij,ij->j", w, m @ w)))
            t[:k, k - p:k] = _project_out(w, m, basis[:, :k])
            theta, y = _ritz(t[:k, :k])
            mw = m @ w
            gram = w.T @ mw
            y_last = y[k - p:k, :nmodes]
            residual = np.sqrt(np.maximum(np.einsum("ij,ik,kj->j", y_last, gram, y_last), 0.0))
            if k >= n or np.all(residual <= tol * theta[:nmodes]):
                return theta[:nmodes], basis[:, :k] @ y[:, :nmodes], True
            if k + p > cap:
                break
            v = _orthonormal_block(w, m, basis[:, :k], rng, scale, gram)
        if restart == MAX_RESTARTS:
            break
        ritz_vectors = basis[:, :k] @ y[:, :keep]
        basis[:, :keep] = ritz_vectors
        t[:, :] = 0.0
        t[np.arange(keep), np.arange(keep)] = theta[:keep]
        k = keep
        v = _orthonormal_block(w, m, basis[:, :k], rng, scale, gram)
    return theta[:nmodes], basis[:, :k] @ y[:, :nmodes], False


def _ritz(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigenpairs of the symmetric matrix whose upper triangle is ``t``, descending."""
    full = np.triu(t) + np.triu(t, 1).T
    theta, y = np.linalg.eigh(full)
    return theta[::-1], y[:, ::-1]


def _project_out(w: np.ndarray, m: sp.spmatrix, q: np.ndarray) -> np.ndarray:
    """w <- w - q (q^T M w), twice (classical Gram-Schmidt twice); returns the coefficients."""
    coeff = q.T @ (m @ w)
    w -= q @ coeff
    again = q.T @ (m @ w)
    w -= q @ again
    return coeff + again


def _orthonormal_block(w: np.ndarray, m: sp.spmatrix, q: np.ndarray, rng: np.random.Generator,
                       scale: float, gram: np.ndarray) -> np.ndarray:
    """An M-orthonormal basis of span(w), M-orthogonal to ``q`` (w is already).

    ``gram`` = w^T M w; ``scale`` = the largest squared M-norm of w's columns before they were
    made orthogonal to ``q``. Directions shorter than DEFLATION relative to it lie numerically in
    span(q) (an invariant subspace was found): they are replaced by random ones, M-orthogonal to q.
    """
    w = w.copy()
    for _ in range(2):                         # SVQB twice (eigen-decomposition of the Gram matrix)
        d, u = np.linalg.eigh(0.5 * (gram + gram.T))
        small = d <= DEFLATION ** 2 * scale
        if np.any(small):
            w = w @ u
            w[:, small] = rng.standard_normal((w.shape[0], int(small.sum())))
            _project_out(w, m, q)
            gram = w.T @ (m @ w)
            d, u = np.linalg.eigh(0.5 * (gram + gram.T))
        w = w @ (u / np.sqrt(d))
        gram, scale = w.T @ (m @ w), 1.0
    return w
