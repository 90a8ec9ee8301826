"""The sparse factorisation backends (structures.sparse_factor) against each other and against
exact residuals; the modal solve gives the same modes on every backend.

References: the residual of each solve (computed with the matrix itself), and the SuperLU
fallback's frequencies for the 2,040-DOF cantilever plate.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from plate_decks import plate_deck
from structures.assembly import assemble
from structures.bdf import read_model
from structures.common.errors import InputError, SolverError
from structures import sparse_factor
from structures.modal import DEFAULT_SHIFT, solve_eigen
from structures.sparse_factor import BACKENDS, ENV_VAR, available_backends, factorize

BACKEND_PARAMS = [pytest.param(name, marks=pytest.mark.skipif(
    name not in available_backends(), reason=f"sparse backend {name} not installed"))
    for name in BACKENDS]


def random_spd(n: int = 800, seed: int = 3) -> sp.csr_matrix:
    """A sparse symmetric, strictly diagonally dominant (so positive definite) matrix."""
    r = sp.random(n, n, density=0.01, random_state=seed)
    a = r + r.T
    return (a + sp.diags(np.asarray(abs(a).sum(axis=1)).ravel() + 1.0)).tocsr()


@pytest.fixture(scope="module")
def plate(tmp_path_factory):
    """K, M and grid of each DOF of a 20 x 16 cantilever CQUAD4 plate (2,040 DOF)."""
    deck = plate_deck(tmp_path_factory.mktemp("plate") / "plate.bdf", nx=20, ny=16,
                      boundary="cantilever")
    system = assemble(read_model(deck))
    return system.K, system.M, system.a_dofs // 6


def relative_residual(a, x, b) -> float:
    return float(np.linalg.norm(a @ x - b) / np.linalg.norm(b))


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_random_spd_system(backend):
    a = random_spd()
    rng = np.random.default_rng(0)
    factor = factorize(a, backend=backend)
    assert factor.backend == backend
    b = rng.standard_normal(a.shape[0])
    x = factor.solve(b)
    assert x.shape == b.shape
    assert relative_residual(a, x, b) < 1e-10
    bb = rng.standard_normal((a.shape[0], 5))
    xx = factor.solve(bb)
    assert xx.shape == bb.shape
    assert relative_residual(a, xx, bb) < 1e-10


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_shifted_plate_system(plate, backend):
    k, m, groups = plate
    assert 2000 <= k.shape[0] <= 2100
    a = (k - DEFAULT_SHIFT * m).tocsc()
    factor = factorize(a, groups=groups, backend=backend)
    b = np.random.default_rng(1).standard_normal((a.shape[0], 3))
    x = factor.solve(b)
    # The thin plate's K - sigma M is ill-conditioned (drilling and bending against membrane
    # stiffness): ||r|| / ||b|| is ~1.0e-10 on every backend, so the check is the normwise
    # backward error of a stable direct solve.
    backward = np.linalg.norm(a @ x - b) / (spla.norm(a) * np.linalg.norm(x) + np.linalg.norm(b))
    assert backward < 1e-16
    assert relative_residual(a, x, b) < 1e-9


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_plate_frequencies_match_dense_lapack(plate, backend, monkeypatch):
    """Reference: LAPACK's dense symmetric-definite solve of M x = mu (K - sigma M) x (scipy
    eigh), independent of the sparse factorisations and of ARPACK."""
    k, m, groups = plate
    sigma = -1.0
    n = k.shape[0]
    mu = sla.eigh(m.toarray(), (k - sigma * m).toarray(), eigvals_only=True,
                  subset_by_index=[n - 10, n - 1])
    lam_ref = np.sort(sigma + 1.0 / mu)
    monkeypatch.setenv(ENV_VAR, backend)
    lam, phi = solve_eigen(k, m, 10, groups=groups)
    np.testing.assert_allclose(np.sqrt(lam), np.sqrt(lam_ref), rtol=1e-8)
    np.testing.assert_allclose(phi.T @ (m @ phi), np.eye(10), atol=1e-8)
    residual = k @ phi - (m @ phi) * lam
    assert np.max(np.linalg.norm(residual, axis=0) / np.linalg.norm(k @ phi, axis=0)) < 1e-6


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_massless_mechanism_raises(backend):
    """Two DOFs joined by a spring, with no mass and no ground: K - sigma M is singular although
    every diagonal entry is positive; and a DOF with neither stiffness nor mass (an empty row)."""
    a = random_spd().tolil()
    a[10, :] = 0.0
    a[:, 10] = 0.0
    a[11, :] = 0.0
    a[:, 11] = 0.0
    a[10, 10] = a[11, 11] = 5.0e6
    a[10, 11] = a[11, 10] = -5.0e6
    with pytest.raises(SolverError, match="massless mechanism"):
        factorize(a.tocsc(), filename="spring.bdf", backend=backend)
    a[10, 11] = a[11, 10] = a[10, 10] = a[11, 11] = 0.0
    with pytest.raises(SolverError, match="massless mechanism"):
        factorize(a.tocsc(), backend=backend)


def test_environment_variable_forces_the_backend(monkeypatch):
    monkeypatch.setenv(ENV_VAR, "superlu")
    assert factorize(random_spd()).backend == "superlu"
    monkeypatch.delenv(ENV_VAR)
    assert factorize(random_spd()).backend == available_backends()[0]


def test_unknown_backend_lists_the_valid_ones(monkeypatch):
    with pytest.raises(InputError, match="pardiso, superlu"):
        factorize(random_spd(), backend="cholmod")
    monkeypatch.setenv(ENV_VAR, "umfpack")
    with pytest.raises(InputError, match=ENV_VAR):
        factorize(random_spd())


@pytest.mark.skipif("pardiso" in available_backends(), reason="pypardiso is installed")
def test_missing_backend_says_how_to_install():
    with pytest.raises(InputError, match="not installed"):
        factorize(random_spd(), backend="pardiso")


@pytest.mark.parametrize("load, cores, expected", [
    (0.2, 2, 2),         # idle machine: both cores
    (1.3, 2, 2),         # about one unit of load: the solver's own earlier runs
    (1.6, 2, 1),         # another program keeps a core busy
    (4.0, 2, 1),         # overloaded: never fewer than one thread
    (3.0, 8, 6),
])
def test_free_cores_leaves_the_busy_ones(monkeypatch, load, cores, expected):
    """free_cores = cores - (round(load average) - 1), at least 1 (hand-computed cases)."""
    monkeypatch.setattr(sparse_factor.os, "getloadavg", lambda: (load, load, load))
    monkeypatch.setattr(sparse_factor.os, "sched_getaffinity", lambda pid: set(range(cores)),
                        raising=False)
    assert sparse_factor.free_cores() == expected


@pytest.mark.skipif("pardiso" not in available_backends(), reason="PARDISO not installed")
def test_pardiso_thread_count_gives_the_same_solution(monkeypatch):
    """One MKL thread and two solve the same system to round-off (residual reference)."""
    a = random_spd(2000, seed=5)
    b = np.random.default_rng(1).standard_normal(a.shape[0])
    solutions = []
    for cores in (1, 2):
        monkeypatch.setattr(sparse_factor, "free_cores", lambda cores=cores: cores)
        factor = factorize(a, backend="pardiso")
        assert factor.threads <= cores
        solutions.append(factor.solve(b))
    for x in solutions:
        assert np.linalg.norm(a @ x - b) <= 1e-12 * np.linalg.norm(b)
    assert np.allclose(solutions[0], solutions[1], rtol=1e-10,
                       atol=1e-12 * np.abs(solutions[0]).max())
