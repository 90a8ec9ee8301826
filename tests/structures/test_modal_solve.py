"""structures.modal.solve_eigen: the sparse shift-invert solve with a lumped mass that leaves DOFs
massless (the Lanczos run on the DOFs with mass alone)."""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from structures import modal


def _pencil(seed: int = 7):
    """A 900-DOF grid pencil (above the dense limit) whose odd DOFs carry no mass."""
    rng = np.random.default_rng(seed)
    side = 30
    line = sp.diags([-np.ones(side - 1), 2 * np.ones(side), -np.ones(side - 1)], [-1, 0, 1])
    k = (sp.kronsum(line, line) + sp.diags(rng.uniform(0.01, 0.5, side * side))).tocsr()
    n = k.shape[0]
    mass = np.where(np.arange(n) % 2 == 0, rng.uniform(0.5, 2.0, n), 0.0)
    return k, mass


def test_lumped_mass_with_massless_dofs_matches_static_condensation():
    """A 900-DOF pencil (above the dense limit) whose odd DOFs carry no mass: eigenvalues and
    shapes against the exact static condensation of the massless DOFs (independent reference:
    K_c = K_mm - K_mo K_oo^-1 K_om, dense scipy.linalg.eigh(K_c, M_mm); massless rows
    phi_o = -K_oo^-1 K_om phi_m)."""
    k, mass = _pencil()
    n = k.shape[0]
    assert n > modal.DENSE_LIMIT
    m = sp.diags(mass).tocsr()
    lam, phi = modal.solve_eigen(k, m, 12)

    dense = k.toarray()
    on, off = np.flatnonzero(mass > 0), np.flatnonzero(mass == 0)
    k_c = dense[np.ix_(on, on)] - dense[np.ix_(on, off)] @ np.linalg.solve(
        dense[np.ix_(off, off)], dense[np.ix_(off, on)])
    ref_lam, ref_m = sla.eigh(k_c, np.diag(mass[on]), subset_by_index=[0, 11])
    ref = np.zeros((n, 12))
    ref[on] = ref_m
    ref[off] = -np.linalg.solve(dense[np.ix_(off, off)], dense[np.ix_(off, on)] @ ref_m)

    np.testing.assert_allclose(lam, ref_lam, rtol=1e-10)
    sign = np.sign(np.einsum("ij,ij->j", phi, ref))
    np.testing.assert_allclose(phi * sign, ref, atol=1e-8 * np.abs(ref).max())
    np.testing.assert_allclose(phi.T @ (m @ phi), np.eye(12), atol=1e-10)
    assert modal.eigen_residuals(k, m, lam, phi).max() < modal.RESIDUAL_TOL


def test_repeated_solves_are_identical_and_leave_the_global_random_state_alone():
    """The Lanczos start vector is fixed: a solve repeated in one process gives the same bits
    (ARPACK's own random start advanced from call to call and let the backward error wander
    over RESIDUAL_TOL), and numpy's global random state is not drawn from."""
    k, mass = _pencil(11)
    m = sp.diags(mass).tocsr()
    state = np.random.get_state()[1].copy()
    first = modal.solve_eigen(k, m, 10)
    for _ in range(3):
        again = modal.solve_eigen(k, m, 10)
        np.testing.assert_array_equal(again[0], first[0])
        np.testing.assert_array_equal(again[1], first[1])
    np.testing.assert_array_equal(np.random.get_state()[1], state)
    assert modal.eigen_residuals(k, m, *first).max() < 0.1 * modal.RESIDUAL_TOL
