"""structures.modal: the eigenpair backward error and the re-shift it triggers."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from plate_decks import plate_deck
from structures import modal
from structures.assembly import assemble
from structures.bdf import read_model

DATA = Path(__file__).resolve().parents[1] / "data"


def test_backward_error_of_exact_and_perturbed_pairs():
    """Dense generalized eigenpairs of a random SPD pencil give round-off; a vector perturbed by
    1e-6 gives a backward error of that order (independent reference: scipy.linalg.eigh)."""
    rng = np.random.default_rng(3)
    a = rng.standard_normal((40, 40))
    k = a @ a.T + 40 * np.eye(40)
    m = np.diag(rng.uniform(0.5, 2.0, 40))
    lam, phi = sla.eigh(k, m)
    exact = modal.eigen_residuals(sp.csr_matrix(k), sp.csr_matrix(m), lam, phi)
    assert np.all(exact < 1e-14)
    bent = phi + 1e-6 * rng.standard_normal(phi.shape)
    perturbed = modal.eigen_residuals(sp.csr_matrix(k), sp.csr_matrix(m), lam, bent)
    assert np.all((perturbed > 1e-8) & (perturbed < 1e-4))


def _count_factorisations(monkeypatch) -> list:
    calls = []
    real = modal.factorize

    def counting(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(modal, "factorize", counting)
    return calls


def test_stiff_plate_low_modes_need_no_second_solve(tmp_path, monkeypatch):
    """The low modes of a stiff cantilever plate (||K phi|| = lambda ||M phi|| is small against
    ||K||) are accurate: the backward error, normalised by |K||phi|, stays at round-off (4e-16)
    and the solve is not repeated (normalised by ||K phi|| it read 1.6e-8 on this plate and 4e-7
    on the 60,000-DOF benchmark plate, and forced a second solve)."""
    deck = plate_deck(tmp_path / "plate.bdf", nx=60, ny=36, boundary="cantilever")
    model = read_model(deck)
    system = assemble(model)
    calls = _count_factorisations(monkeypatch)
    lam, phi = modal.solve_eigen(system.K, system.M, 10, groups=system.a_dofs // 6)
    assert len(calls) == 1
    assert np.all(modal.eigen_residuals(system.K, system.M, lam, phi) < 1e-13)


def test_cylinder_at_the_default_shift_is_solved_again(monkeypatch):
    """Free-free cylinder, SuperLU, default shift: the first solve's backward errors reach 1e-3, so
    the solve is repeated once at a tenth of the lowest elastic eigenvalue."""
    monkeypatch.setenv("FTP_SPARSE_BACKEND", "superlu")
    system = assemble(read_model(DATA / "dakota_cylinder" / "modal.bdf"))
    calls = _count_factorisations(monkeypatch)
    lam, phi = modal.solve_eigen(system.K, system.M, 20, groups=system.a_dofs // 6)
    assert len(calls) == 2
    assert np.all(modal.eigen_residuals(system.K, system.M, lam[6:], phi[:, 6:])
                  < modal.RESIDUAL_TOL)


def test_a_missed_rigid_body_mode_is_found_by_a_second_solve(tmp_path):
    """The free-free Dakota cylinder as the diagnose workflow wrote it after a round (E 9.7828e6,
    the end mass 1026.35, a mirror pair of CONM2s of 0.1974 with 0.00867 rotary inertia at grids
    24 and 25): solved for 8 modes, the Lanczos solve found five of its six zero eigenvalues
    (and so took its first elastic mode for a rigid-body one) until compute_modes solved again
    with more modes. Independent reference: the 20-mode solve, whose first eight frequencies
    it must give (1348.36, 1348.72 Hz elastic), and six rigid-body modes."""
    text = (DATA / "dakota_cylinder" / "modal.bdf").read_text()
    old_mat, old_mass = ("MAT1     101     1.+7            .35     .1",
                         "CONM2    501     501             1000.   0.      0.      0.")
    assert old_mat in text and old_mass in text
    extra = "".join(f"CONM2,{eid},{grid},,.1973912,0.,0.,0.\n,.0086707,0.,.0086707,0.,0.,"
                    ".0086707\n" for eid, grid in ((504, 24), (505, 25)))
    text = (text.replace(old_mat, "MAT1,101,9782830.,,.35,.1")
            .replace(old_mass, "CONM2,501,501,,1026.35,0.,0.,0.")
            .replace("ENDDATA", extra + "ENDDATA"))
    deck = tmp_path / "cylinder.bdf"
    deck.write_text(text)
    model = read_model(deck)
    eight = modal.compute_modes(model, 8)
    twenty = modal.compute_modes(model, 20)
    assert int(eight.attrs["rigid_modes"]) == 6
    np.testing.assert_allclose(eight["frequency"].values[6:],
                               twenty["frequency"].values[6:8], rtol=1e-9)
    assert eight["frequency"].values[6] > 1000.0
