"""Beams against Euler-Bernoulli theory; rigid-body modes; invariance to frames and mass offsets."""
from __future__ import annotations

import numpy as np
import pytest

from structures.bdf import read_model
from structures.massprops import mass_properties
from structures.modal import compute_modes
from tests.structures.beam_decks import (CANTILEVER_BETA_L, FREE_FREE_BETA_L, INERTIA,
                                         bending_frequencies, beam_deck, cord2r)


def _rotation(axis, angle_deg):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    a = np.deg2rad(angle_deg)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(a) * k + (1 - np.cos(a)) * k @ k


def test_cantilever_first_four_bending_modes_within_0p2_percent(tmp_path):
    model = read_model(beam_deck(tmp_path / "cantilever.bdf", plane_only=True))
    freq = compute_modes(model, 4)["frequency"].values
    exact = bending_frequencies(CANTILEVER_BETA_L)
    np.testing.assert_allclose(freq, exact, rtol=2e-3)


def test_cantilever_two_planes_give_pairs(tmp_path):
    """With I2 = 4 I1 the out-of-plane family is exactly twice the in-plane one."""
    model = read_model(beam_deck(tmp_path / "c.bdf", i2=4 * INERTIA, nmodes=8))
    freq = compute_modes(model, 8)["frequency"].values
    plane1 = bending_frequencies(CANTILEVER_BETA_L)
    for f in plane1[:3]:
        assert np.min(np.abs(freq / f - 1)) < 2e-3
        assert np.min(np.abs(freq / (2 * f) - 1)) < 2e-3


@pytest.fixture(scope="module")
def free_free(tmp_path_factory):
    path = beam_deck(tmp_path_factory.mktemp("ff") / "free.bdf", support="free", nmodes=14,
                     element="CBEAM")
    model = read_model(path)
    return model, compute_modes(model, 14)


def test_free_free_has_exactly_six_rigid_body_modes(free_free):
    _, modes = free_free
    freq = modes["frequency"].values
    first_flexible = bending_frequencies(FREE_FREE_BETA_L[0])
    assert np.sum(freq < 1e-4 * first_flexible) == 6
    assert freq[6] > 0.99 * first_flexible


def test_free_free_bending_within_0p2_percent(free_free):
    _, modes = free_free
    flexible = modes["frequency"].values[6:]
    exact = bending_frequencies(FREE_FREE_BETA_L)
    # I1 = I2: every bending frequency appears twice (two planes).
    np.testing.assert_allclose(flexible[0:8:2], exact, rtol=2e-3)
    np.testing.assert_allclose(flexible[1:8:2], exact, rtol=2e-3)


def test_modes_are_mass_normalised(free_free):
    model, modes = free_free
    from structures.assembly import assemble_g
    _, m_basic = assemble_g(model)
    phi = modes["shape"].values
    np.testing.assert_allclose(phi @ (m_basic @ phi.T), np.eye(len(phi)), atol=1e-8)


def test_displacement_frame_rotation_changes_nothing(tmp_path):
    """Grids with a rotated CD frame: same frequencies, same basic-frame shapes (I2 = 4 I1 so that
    no two modes share a frequency and shapes are unique up to sign)."""
    coords = cord2r(5, (0, 0, 0), _rotation((1, 2, 3), 37) @ [0, 0, 1],
                    _rotation((1, 2, 3), 37) @ [1, 0, 0])
    ref = compute_modes(read_model(beam_deck(tmp_path / "a.bdf", nmodes=6, i2=4 * INERTIA)), 6)
    rot = compute_modes(read_model(beam_deck(tmp_path / "b.bdf", cd=5, coords=coords, nmodes=6,
                                             i2=4 * INERTIA)), 6)
    np.testing.assert_allclose(rot["frequency"], ref["frequency"], rtol=1e-9)
    a, b = ref["shape"].values, rot["shape"].values
    mac = (a @ b.T) ** 2 / np.outer((a * a).sum(1), (b * b).sum(1))
    assert np.all(np.diag(mac) > 1 - 1e-8)


def test_grids_in_a_rotated_cp_frame_change_nothing(tmp_path):
    coords = cord2r(7, (1.0, -2.0, 0.5), _rotation((0, 1, 1), 25) @ [0, 0, 1] + [1.0, -2.0, 0.5],
                    _rotation((0, 1, 1), 25) @ [1, 0, 0] + [1.0, -2.0, 0.5])
    ref = compute_modes(read_model(beam_deck(tmp_path / "a.bdf", nmodes=6)), 6)
    model = read_model(beam_deck(tmp_path / "b.bdf", cp=7, coords=coords, nmodes=6))
    np.testing.assert_allclose(model.grids.xyz[-1], [10.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(compute_modes(model, 6)["frequency"], ref["frequency"], rtol=1e-9)


def test_rotating_the_whole_structure_changes_frequencies_not(tmp_path):
    rot = _rotation((1, -1, 2), 50)
    ref = read_model(beam_deck(tmp_path / "a.bdf", support="free", nmodes=12, element="CBEAM"))
    turned = read_model(beam_deck(tmp_path / "b.bdf", support="free", nmodes=12, rotation=rot,
                                  element="CBEAM"))
    fa = compute_modes(ref, 12)["frequency"].values[6:]
    fb = compute_modes(turned, 12)["frequency"].values[6:]
    np.testing.assert_allclose(fb, fa, rtol=1e-8)
    pa, pb = mass_properties(ref), mass_properties(turned)
    assert pb.mass == pytest.approx(pa.mass, rel=1e-12)
    np.testing.assert_allclose(pb.cg, rot @ pa.cg, atol=1e-10)
    np.testing.assert_allclose(pb.inertia, rot @ pa.inertia @ rot.T, atol=1e-8 * pa.inertia.max())


def test_offset_conm2_equals_mass_on_rigidly_attached_grid(tmp_path):
    """A CONM2 with offset (and inertia) is the same as the mass on a grid tied by RBE2."""
    conm_offset = "CONM2,100,41,,50.0,0.3,0.2,-0.4\n,2.0,0.1,3.0,0.2,0.3,4.0"
    attached = ("GRID,900,,10.3,0.2,-0.4\nRBE2,901,41,123456,900\n"
                "CONM2,100,900,,50.0\n,2.0,0.1,3.0,0.2,0.3,4.0")
    a = read_model(beam_deck(tmp_path / "a.bdf", extra=conm_offset, nmodes=8))
    b = read_model(beam_deck(tmp_path / "b.bdf", extra=attached, nmodes=8))
    np.testing.assert_allclose(compute_modes(a, 8)["frequency"], compute_modes(b, 8)["frequency"],
                               rtol=1e-9)
    pa, pb = mass_properties(a), mass_properties(b)
    assert pa.mass == pytest.approx(pb.mass, rel=1e-14)
    np.testing.assert_allclose(pa.cg, pb.cg, atol=1e-12)
    np.testing.assert_allclose(pa.inertia, pb.inertia, rtol=1e-12, atol=1e-9)


def test_free_free_cbar_without_rotary_inertia_is_a_massless_mechanism(tmp_path):
    from structures.common.errors import SolverError
    model = read_model(beam_deck(tmp_path / "free_cbar.bdf", support="free", nmodes=8))
    with pytest.raises(SolverError, match="massless mechanism"):
        compute_modes(model, 8)


@pytest.mark.parametrize("kind", ["C", "S"])
def test_cylindrical_and_spherical_displacement_frames_change_nothing(tmp_path, kind):
    """CD frames whose axes vary from grid to grid (CORD2C / CORD2S off the beam axis)."""
    coords = cord2r(9, (3.0, -2.0, 1.0), (3.5, -1.0, 2.0), (4.0, -2.0, 0.0), kind=kind)
    ref = compute_modes(read_model(beam_deck(tmp_path / "a.bdf", nmodes=6, i2=4 * INERTIA)), 6)
    model = read_model(beam_deck(tmp_path / "b.bdf", nmodes=6, i2=4 * INERTIA, coords=coords,
                                 cd=9, vector_in_basic=True))
    assert len(np.unique(np.round(model.grids.cd_axes, 8), axis=0)) == len(model.grids)
    modes = compute_modes(model, 6)
    np.testing.assert_allclose(modes["frequency"], ref["frequency"], rtol=1e-9)
    a, b = ref["shape"].values, modes["shape"].values
    mac = (a @ b.T) ** 2 / np.outer((a * a).sum(1), (b * b).sum(1))
    assert np.all(np.diag(mac) > 1 - 1e-8)
