"""Exact rigid-body modes (structures.modal.rigid_body_modes) and the SUPORT / SUPORT1 r-set.

References: the rigid-body motions of a uniform free-free beam (plunge amplitude 1/sqrt(rho A L),
pitch 1/sqrt(rho A L^3 / 12) about the mid-point, rotary inertia 1.2e-4 of that), the eigenvalues of
the same (K, M) before the rigid modes are made exact, and Nastran's bah_plane F06 (free in plunge
and pitch by SPC1 1246 at grid 1).
"""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from structures.assembly import assemble
from structures.bdf import read_model
from structures.common.errors import InputError, MissingReferenceError
from structures.massprops import mass_properties
from structures.modal import RIGID_TOL, compute_modes, rigid_body_modes, solve_eigen
from structures.modes import elastic_index, read_modes, rigid_index, write_modes
from structures.nastran_results import read_f06_eigenvalues
from tests.structures.beam_decks import AREA, LENGTH, RHO, beam_deck

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data"
BAH = DATA / "bah_plane"


def _orthonormality(ds, system):
    """Phi^T M Phi with the g-set basic mass of the assembled system (translations, rotations)."""
    shapes = ds["shape"].values
    return shapes @ (system.m_basic @ shapes.T)


@pytest.mark.parametrize("deck, nmodes", [("beam", 12), ("cylinder", 14), ("x56", 10)])
def test_free_free_models_have_six_exact_rigid_modes(tmp_path, deck, nmodes):
    """Free-free CBEAM beam, CQUAD4 cylinder and the X-56A-class aircraft (CBUSH joints, RBE2s;
    its rigid motions' constraint misfit is round-off, 1e-16, not zero): 6 modes at 0.0 Hz,
    Phi^T M Phi = I to 1e-12 (rigid-elastic blocks zero), the elastic frequencies those of the
    plain eigen-solve to 1e-9."""
    path = {"beam": lambda: beam_deck(tmp_path / "beam.bdf", support="free", element="CBEAM"),
            "cylinder": lambda: DATA / "dakota_cylinder" / "modal.bdf",
            "x56": lambda: ROOT / "data" / "x56_like" / "x56_fffw.bdf"}[deck]()
    model = read_model(path)
    system = assemble(model, warn=False)
    ds = compute_modes(model, nmodes, system=system)
    lam, _ = solve_eigen(system.K, system.M, nmodes, groups=system.a_dofs // 6)
    freq = ds["frequency"].values
    assert np.all(freq[:6] == 0.0)
    assert list(ds["rigid_motion"].values[:6]) == ["surge", "sway", "plunge", "roll", "pitch",
                                                   "yaw"]
    assert ds.attrs["rigid_modes"] == 6 and ds.attrs["rigid_residual"] <= RIGID_TOL
    gram = _orthonormality(ds, system)
    assert np.abs(gram - np.eye(nmodes)).max() < 1e-12
    assert np.abs(gram[:6, 6:]).max() < 1e-12
    np.testing.assert_allclose(freq[6:], np.sqrt(lam[6:]) / (2 * np.pi), rtol=1e-9)


def test_free_free_beam_rigid_shapes_are_analytic(tmp_path):
    """Plunge: u_z = 1 / sqrt(m) everywhere; pitch about the mid-point (the CG): theta_y =
    1 / sqrt(m L^2 / 12) (rotary inertia rho I L adds 1.2e-4), u_z = -theta_y (x - L/2)."""
    model = read_model(beam_deck(tmp_path / "beam.bdf", support="free", element="CBEAM"))
    ds = compute_modes(model, 8)
    mass = RHO * AREA * LENGTH
    plunge = ds["shape"].sel(mode=3).values.reshape(-1, 6)
    sign = np.sign(plunge[0, 2])
    np.testing.assert_allclose(sign * plunge[:, 2], 1 / np.sqrt(mass), rtol=1e-12)
    assert np.abs(plunge[:, [0, 1, 3, 4, 5]]).max() < 1e-12 / np.sqrt(mass)
    pitch = ds["shape"].sel(mode=5).values.reshape(-1, 6)
    theta = pitch[:, 4] * np.sign(pitch[0, 4])
    np.testing.assert_allclose(theta, 1 / np.sqrt(mass * LENGTH ** 2 / 12), rtol=2e-4)
    x = model.grids.xyz[:, 0]
    np.testing.assert_allclose(pitch[:, 2], -pitch[:, 4] * (x - LENGTH / 2),
                               atol=1e-12 * np.abs(pitch[:, 2]).max())


def test_bah_plane_two_rigid_modes_pure_plunge_and_pitch_about_the_cg():
    """SPC1 1246 at grid 1 leaves plunge and pitch: mode 1 a uniform u_z, mode 2 a uniform
    theta_y turning about the CG's x (M-orthogonal to plunge), elastic modes as Nastran's F06."""
    model = read_model(BAH / "bah_plane.bdf")
    ds = compute_modes(model)
    assert list(ds["rigid_motion"].values[:3]) == ["plunge", "pitch", ""]
    assert np.all(ds["frequency"].values[:2] == 0.0)
    plunge = ds["shape"].sel(mode=1).values.reshape(-1, 6)
    pitch = ds["shape"].sel(mode=2).values.reshape(-1, 6)
    props = mass_properties(model)
    np.testing.assert_allclose(np.abs(plunge[:, 2]), 1 / np.sqrt(props.mass), rtol=1e-12)
    assert np.abs(plunge[:, [0, 1, 3, 4, 5]]).max() < 1e-14
    assert np.ptp(pitch[:, 4]) < 1e-12 * np.abs(pitch[:, 4]).max()
    assert np.abs(pitch[:, [1, 3, 5]]).max() < 1e-14
    x, z = model.grids.xyz[:, 0], model.grids.xyz[:, 2]
    # u = theta x r about (x_cg, z of grid 1, whose x the SPC fixes): u_x = theta (z - z_1).
    np.testing.assert_allclose(pitch[:, 2], -pitch[:, 4] * (x - props.cg[0]),
                               atol=1e-10 * np.abs(pitch[:, 2]).max())
    np.testing.assert_allclose(pitch[:, 0], pitch[:, 4] * (z - z[model.grids.index([1])[0]]),
                               atol=1e-10 * np.abs(pitch[:, 2]).max())
    ref = read_f06_eigenvalues(BAH / "bah_plane.f06").frequency.values[:8]
    np.testing.assert_allclose(ds["frequency"].values[2:], ref[2:], rtol=2e-6)


def test_spring_supported_plate_has_no_rigid_mode():
    """The two-mode flutter plate on pitch and plunge springs: its motions carry strain energy."""
    model = read_model(DATA / "two_mode_flutter" / "0012_flutter.bdf")
    phi, names = rigid_body_modes(model, assemble(model, warn=False))
    assert phi.shape[1] == 0 and names == []
    assert compute_modes(model).attrs["rigid_modes"] == 0


def _bah_variant(tmp_path, case: str = "", bulk: str = "") -> Path:
    """bah_plane.bdf with extra case-control and bulk lines (its INCLUDEs copied beside it)."""
    for inc in BAH.glob("*.inc"):
        shutil.copy(inc, tmp_path / inc.name)
    text = (BAH / "bah_plane.bdf").read_text()
    text = text.replace("SPC = 101\n", f"SPC = 101\n{case}\n").replace(
        "SPC1,101,1246,1\n", f"SPC1,101,1246,1\n{bulk}\n")
    path = tmp_path / "bah_suport.bdf"
    path.write_text(text)
    return path


def _span_equal(a, b, m):
    """Same column space: b's M-projection on a (M-orthonormal) is b."""
    return np.abs(a @ (a.T @ (m @ b)) - b).max() < 1e-10 * np.abs(b).max()


@pytest.mark.parametrize("case, bulk", [("", "SUPORT,1,35"), ("SUPORT1 = 7", "SUPORT1,7,1,53"),
                                        ("SUPORT1 = 7", "SUPORT,1,3\nSUPORT1,7,1,5")])
def test_suport_and_suport1_give_the_geometric_rigid_modes(tmp_path, case, bulk):
    """The r-set (grid 1, components 3 and 5) spans the same two rigid modes as the SPC-free
    directions; the modes are M-orthonormal, plunge first."""
    model = read_model(_bah_variant(tmp_path, case, bulk))
    assert sorted(model.suport) == [(1, 0b10100)] or sorted(model.suport) == [(1, 0b100),
                                                                              (1, 0b10000)]
    system = assemble(model, warn=False)
    phi, names = rigid_body_modes(model, system)
    plain = read_model(BAH / "bah_plane.bdf")
    ref, _ = rigid_body_modes(plain, assemble(plain, warn=False))
    assert names == ["plunge", "pitch"]
    assert np.abs(phi.T @ (system.M @ phi) - np.eye(2)).max() < 1e-12
    assert _span_equal(ref, phi, system.M)


def test_unselected_suport1_is_ignored(tmp_path):
    """Nastran uses a SUPORT1 set only when the case control selects it."""
    assert read_model(_bah_variant(tmp_path, "", "SUPORT1,7,1,35")).suport == ()


@pytest.mark.parametrize("case, bulk, error, words", [
    ("SUPORT1 = 8", "SUPORT1,7,1,35", MissingReferenceError, ["SUPORT1 8", "not defined"]),
    ("", "SUPORT,999,35", MissingReferenceError, ["SUPORT 999", "GRID 999"]),
    ("", "SUPORT,1,3", InputError, ["SUPORT 1", "do not determine", "2 rigid-body"]),
    ("", "SUPORT,1,135", InputError, ["SUPORT 1", "component 1", "constrained"]),
    ("", "SUPORT,1,37", InputError, ["SUPORT", "invalid component '7'"]),
])
def test_bad_suport_names_file_card_grid_and_fix(tmp_path, case, bulk, error, words):
    path = _bah_variant(tmp_path, case, bulk)
    with pytest.raises(error) as info:
        model = read_model(path)
        rigid_body_modes(model, assemble(model, warn=False))
    text = str(info.value)
    assert str(path) in text and "Fix:" in text
    for word in words:
        assert word in text


def test_modes_file_keeps_the_contract_and_the_rigid_names(tmp_path):
    """modes.nc (DESIGN.md section 6) keeps its variables, coordinates and attrs; the rigid-body
    names (``rigid_motion``) and the residual check survive the round trip."""
    ds = compute_modes(read_model(BAH / "bah_plane.bdf"))
    write_modes(ds, tmp_path / "modes.nc")
    back = read_modes(tmp_path / "modes.nc")
    assert {"frequency", "shape", "generalized_mass"} <= set(back.data_vars)
    assert {"grid", "component", "mode", "rigid_motion"} <= set(back.coords)
    assert back["shape"].dims == ("mode", "dof") and back["frequency"].attrs["units"] == "Hz"
    assert list(back["mode"].values) == list(range(1, 9))
    assert {"source", "deck", "units"} <= set(back.attrs)
    assert list(back["rigid_motion"].values[:3]) == ["plunge", "pitch", ""]
    assert back.attrs["rigid_modes"] == 2 and back.attrs["rigid_residual"] <= RIGID_TOL
    assert rigid_index(back).tolist() == [0, 1]
    assert elastic_index(back).tolist() == list(range(2, 8))
    unnamed = back.drop_vars("rigid_motion")          # an OP2's modes: none marked rigid
    assert rigid_index(unnamed).size == 0 and elastic_index(unnamed).tolist() == list(range(8))


def test_rigid_count_check_refuses_to_replace_an_elastic_mode():
    """exact_rigid_modes replaces the lowest eigenpairs: with 2 rigid motions and only one zero
    eigenvalue below the elastic ones, the solve stops with an error naming the counts."""
    from types import SimpleNamespace

    from structures.common.errors import SolverError
    from structures.modal import _check_rigid_count

    model = SimpleNamespace(filename="free.bdf")
    _check_rigid_count(model, np.array([1e-12, -3e-13, 40.0, 90.0]), 2)        # both zero: fine
    # a stiff model's round-off (1.6e-6 of the first elastic one, measured on the X-56A-class
    # model with a tapered main-gear leg) is zero too
    _check_rigid_count(model, np.array([1.6e-6 * 40.0, -3e-13, 40.0, 90.0]), 2)
    with pytest.raises(SolverError, match="2 rigid-body motions, but only 1"):
        _check_rigid_count(model, np.array([1e-12, 38.0, 40.0, 90.0]), 2)


def test_grounded_spring_leaves_five_strain_free_rigid_modes(tmp_path):
    """The free-free CBEAM beam with a grounded CELAS2 in y at its end grid (stiffness 1e-3 of
    the beam's 12 E I / L^3, so its backward error 1e-3-ish is far above RIGID_TOL): the spring
    holds sway and every rotation that moves the end grid sideways, so 5 rigid motions remain
    (the yaw about the end grid, not sway) and each carries no strain energy (backward error <=
    RIGID_TOL). The elastic modes are those of a plain dense eigen-solution of the same (K, M)
    (scipy.linalg.eigh, no rigid-mode replacement): frequencies to 1e-9, MAC 1 - 1e-8 (the
    elastic modes are M-orthogonalised against the rigid ones, which must be exact for that;
    I2 = 2 I1 keeps the two bending planes apart, so every mode is simple)."""
    import scipy.linalg as sla
    from structures.modal import _backward_error
    from tests.structures.beam_decks import E, INERTIA

    k = 1e-3 * 12 * E * INERTIA / LENGTH ** 3
    model = read_model(beam_deck(tmp_path / "beam.bdf", support="free", element="CBEAM",
                                 nel=10, i2=2.0 * INERTIA, extra=f"CELAS2,900,{k!r},11,2"))
    system = assemble(model, warn=False)
    phi_r, names = rigid_body_modes(model, system)
    assert names == ["surge", "plunge", "roll", "pitch", "yaw"]
    assert _backward_error(system.K, phi_r).max() <= RIGID_TOL
    ds = compute_modes(model, 12, system=system)
    shift = -1.0
    mu, vec = sla.eigh(system.M.toarray(), (system.K - shift * system.M).toarray())
    order = np.argsort(-mu)[:12]
    lam, vec = shift + 1.0 / mu[order], vec[:, order]
    shapes = (system.rotation @ (system.T @ vec)).T[5:]
    freq = ds["frequency"].values
    np.testing.assert_allclose(freq[5:], np.sqrt(lam[5:]) / (2 * np.pi), rtol=1e-9)
    ours = ds["shape"].values[5:]
    mac = np.einsum("ij,ij->i", ours, shapes) ** 2 / (np.einsum("ij,ij->i", ours, ours)
                                                       * np.einsum("ij,ij->i", shapes, shapes))
    assert mac.min() > 1.0 - 1e-8
