"""structures.modal.solve_eigen: the sparse shift-invert solve with a lumped mass that leaves DOFs
massless (the Lanczos run on the DOFs with mass alone); a stiff free-free model against a
massless mechanism (the singularity test and its repeat at a larger shift); compute_modes on a
model with few or no degrees of freedom carrying mass."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from structures import modal
from structures.bdf import read_model
from structures.sparse_factor import PIVOT_RATIO, MasslessMechanism, factorize
from tests.structures.spring_decks import CHAIN_FREQUENCY, spring_chain


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


def _stiff_chain(n: int, k: float = 1.0e14):
    """A free-free chain of ``n`` unit masses on ``n - 1`` springs of stiffness ``k``, and its
    exact eigenvalues lambda_j = 4 k sin^2(j pi / (2 n)), j = 0 .. n - 1 (the discrete wave
    equation's standing waves)."""
    line = sp.diags([-np.ones(n - 1), np.r_[1.0, 2.0 * np.ones(n - 2), 1.0], -np.ones(n - 1)],
                    [-1, 0, 1])
    exact = 4.0 * k * np.sin(np.arange(n) * np.pi / (2.0 * n)) ** 2
    return (k * line).tocsr(), sp.identity(n, format="csr"), exact


@pytest.mark.parametrize("n", [40, 700], ids=["dense", "sparse"])
def test_a_stiff_free_free_model_is_not_a_mechanism(n):
    """Its rigid-body pivot is about -sigma n m against diagonal entries 2 k: at the default shift
    below PIVOT_RATIO (the singularity test fails), at SHIFT_RETRY sigma above it. The solve
    repeats at the larger shift and gives the exact eigenvalues: to 1e-9 from the sparse solve
    (its residual check moves the shift once more, to -lambda_1 / 10), to the dense solve's
    a-priori accuracy eps lambda / |sigma| (:mod:`structures.modal`; 5.5e-5 here, 3e-6
    measured)."""
    k, m, exact = _stiff_chain(n)
    shifted = (k - modal.DEFAULT_SHIFT * m).toarray()
    pivots = np.diag(sla.cholesky(shifted, lower=True)) ** 2 / np.diag(shifted)
    assert pivots.min() < PIVOT_RATIO < modal.SHIFT_RETRY * pivots.min()
    if n > modal.DENSE_LIMIT:
        with pytest.raises(MasslessMechanism):
            factorize(k - modal.DEFAULT_SHIFT * m)
    lam, phi = modal.solve_eigen(k, m, 8)
    sigma = modal.SHIFT_RETRY * modal.DEFAULT_SHIFT
    rtol = 1e-9 if n > modal.DENSE_LIMIT else np.finfo(float).eps * exact[7] / abs(sigma)
    np.testing.assert_allclose(lam[1:], exact[1:8], rtol=rtol)
    assert abs(lam[0]) < 1e-8 * exact[1]
    gram = phi.T @ (m @ phi)
    np.testing.assert_allclose(np.diag(gram), 1.0, rtol=1e-12)
    if n > modal.DENSE_LIMIT:                      # the dense shapes err by the same eps / |sigma|
        np.testing.assert_allclose(gram[1:, 1:], np.eye(7), atol=1e-10)


@pytest.mark.parametrize("n", [40, 700], ids=["dense", "sparse"])
def test_a_massless_mechanism_still_raises(n):
    """The same chain with one end DOF cut loose and massless: no shift gives it a pivot."""
    k, m, _ = _stiff_chain(n, 1.0)
    k, m = k.tolil(), m.tolil()
    k[0, :] = 0.0
    k[:, 0] = 0.0
    m[0, 0] = 0.0
    with pytest.raises(MasslessMechanism, match="massless mechanism"):
        modal.solve_eigen(k.tocsr(), m.tocsr(), 4)


def test_a_model_has_as_many_modes_as_degrees_of_freedom_carrying_mass(tmp_path):
    """Three DOFs, one with mass: one mode whatever is asked (by default, by argument, by the
    deck's EIGRL ND), at the hand-condensed frequency. Before, a request between the DOFs with
    mass and all DOFs raised "only 1 ... carry mass; 3 modes were asked for" and one above all
    DOFs returned the DOFs with mass."""
    model = read_model(spring_chain(tmp_path / "chain.bdf"))
    for nmodes in (None, 1, 3, 20):
        ds = modal.compute_modes(model, nmodes)
        np.testing.assert_allclose(ds.frequency.values, [CHAIN_FREQUENCY], rtol=1e-12)
    ds = modal.compute_modes(read_model(spring_chain(tmp_path / "eigrl.bdf", 2)))
    np.testing.assert_allclose(ds.frequency.values, [CHAIN_FREQUENCY], rtol=1e-12)
    assert ds.attrs["modes_requested"] == 2


def test_a_model_without_mass_raises_naming_the_file_and_the_fix(tmp_path):
    path = spring_chain(tmp_path / "nomass.bdf", mass=False)
    with pytest.raises(modal.SolverError, match=r"nomass\.bdf: no degree of freedom carries "
                       r"mass.*Fix: add mass"):
        modal.compute_modes(read_model(path))
