"""Block shift-invert Lanczos (structures.block_lanczos) against dense generalized eigensolutions.

Reference: scipy.linalg.eigh on the same (K, M) pencil, including a singular M (massless DOFs),
a six-fold eigenvalue (free-free rigid-body modes) and the thick-restart path.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from structures.block_lanczos import block_lanczos

SHIFT = -1.0


def pencil(n: int = 700, massless: int = 100, rigid: int = 6, seed: int = 5):
    """A sparse SPD-plus-null-space K (``rigid`` zero eigenvalues) and a diagonal M that is zero
    on ``massless`` DOFs."""
    rng = np.random.default_rng(seed)
    r = sp.random(n, n, density=0.01, random_state=seed)
    a = r + r.T
    k = (a + sp.diags(np.asarray(abs(a).sum(axis=1)).ravel() + rng.uniform(1.0, 50.0, n))).toarray()
    null = np.linalg.qr(rng.standard_normal((n, rigid)))[0]
    k = k - null @ (null.T @ k) - (k @ null) @ null.T + null @ (null.T @ k @ null) @ null.T
    mass = rng.uniform(0.5, 2.0, n)
    mass[rng.choice(n, massless, replace=False)] = 0.0
    return sp.csr_matrix(0.5 * (k + k.T)), sp.diags(mass).tocsr()


def dense_reference(k, m, nmodes):
    a = (k - SHIFT * m).toarray()
    mu, vec = sla.eigh(m.toarray(), a)
    return mu[::-1][:nmodes], vec[:, ::-1][:, :nmodes]


def run(k, m, nmodes, **kwargs):
    a = (k - SHIFT * m).toarray()
    cho = sla.cho_factor(a)
    return block_lanczos(lambda b: sla.cho_solve(cho, b), m, nmodes, **kwargs)


def test_matches_dense_with_massless_dofs_and_rigid_modes():
    k, m = pencil()
    theta, x, converged = run(k, m, 20)
    ref, _ = dense_reference(k, m, 20)
    assert converged
    np.testing.assert_allclose(theta, ref, rtol=1e-10)
    np.testing.assert_allclose(theta[:6], 1.0 / (0.0 - SHIFT), rtol=1e-10)   # six-fold root
    np.testing.assert_allclose(x.T @ (m @ x), np.eye(20), atol=1e-10)
    lam = SHIFT + 1.0 / theta
    residual = k @ x - (m @ x) * lam
    assert np.max(np.linalg.norm(residual, axis=0)) < 1e-7 * np.max(np.abs(k).sum(axis=1))


def test_thick_restart_gives_the_same_pairs():
    k, m = pencil(seed=7)
    theta, x, converged = run(k, m, 15, block=4, max_vectors=40)
    ref, _ = dense_reference(k, m, 15)
    assert converged
    np.testing.assert_allclose(theta, ref, rtol=1e-10)
    np.testing.assert_allclose(x.T @ (m @ x), np.eye(15), atol=1e-10)


def test_reports_no_convergence():
    k, m = pencil(seed=9)
    _, _, converged = run(k, m, 15, block=2, max_vectors=22, tol=1e-15)
    assert not converged


def test_independent_of_the_start_block():
    k, m = pencil(seed=11)
    first, _, _ = run(k, m, 12, seed=0)
    second, _, _ = run(k, m, 12, seed=1)
    np.testing.assert_allclose(first, second, rtol=1e-10)
