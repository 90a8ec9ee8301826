"""Suspension modes among test modes (structures/suspension.py).

References: rigid-body motions written by hand (a translation reads its direction cosine, a
rotation theta x r); the share of white noise outside a 6-dimensional span, (1 + 6 s^2 / n) /
(1 + s^2) in expectation; the glider-like frame of the blind study hung on soft grounded springs
(its six lowest modes are its suspension, solved by our solver); the BAH wing's half model
(tests/data/bah_plane, a public deck), whose constraints leave it two rigid-body motions.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from structures.bdf import read_model
from structures.common.errors import InputError
from structures.gvt import make_gvt_dataset
from structures.modal import compute_modes
from structures.modes import elastic_index
from structures.mystran import mystran_executable
from structures.suspension import (RIGID_SHARE, model_motions, rigid_body_readings,
                                   rigid_body_share, suspension_modes, without_suspension)
from plate_decks import plate_deck
from tests.pipeline.diagnose.truth import frame
from tests.pipeline.diagnose.truth.wingbox import mystran_modes

DATA = Path(__file__).resolve().parents[1] / "data"


def _layout(n_grids: int = 40, seed: int = 0):
    rng = np.random.default_rng(seed)
    xyz = rng.uniform(-5.0, 5.0, (n_grids, 3))
    position = np.repeat(xyz, 3, axis=0)
    component = np.tile([1, 2, 3], n_grids)
    return position, component


def test_readings_by_hand():
    """Sensors at (1, 0, 0) and (-1, 0, 0) along y and a rotation sensor about z at the origin
    (the centroid): theta_z e_z x r moves the first by +theta along y, the second by -theta; the
    rotation sensor reads theta_z itself."""
    r = rigid_body_readings([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 0.0]], [2, 2, 6])
    np.testing.assert_array_equal(r, [[0, 1, 0, 0, 0, 1], [0, 1, 0, 0, 0, -1],
                                      [0, 0, 0, 0, 0, 1]])
    with pytest.raises(InputError, match="components 1-6"):
        rigid_body_readings([[0.0, 0.0, 0.0]], [7])


def test_rigid_motion_is_all_share_and_noise_lowers_it_as_expected():
    position, component = _layout()
    readings = rigid_body_readings(position, component)
    rng = np.random.default_rng(1)
    rigid = rng.standard_normal((50, 6)) @ readings.T                     # (50, 120)
    np.testing.assert_allclose(rigid_body_share(rigid, position, component), 1.0, rtol=1e-12)
    s, n = 0.05, component.size
    rms = np.sqrt(np.mean(rigid ** 2, axis=1, keepdims=True))
    noisy = rigid + s * rms * rng.standard_normal(rigid.shape)
    expected = (1 + 6 * s ** 2 / n) / (1 + s ** 2)                        # 0.99752
    assert abs(np.mean(rigid_body_share(noisy, position, component)) - expected) < 5e-4
    # the share does not depend on where the positions' origin is
    moved = rigid_body_share(noisy, position + [100.0, -3.0, 7.0], component)
    np.testing.assert_allclose(moved, rigid_body_share(noisy, position, component), rtol=1e-10)


def test_a_shape_outside_the_rigid_span_has_none():
    position, component = _layout()
    readings = rigid_body_readings(position, component)
    q, _ = np.linalg.qr(readings)
    t = np.random.default_rng(2).standard_normal((3, component.size))
    t -= (t @ q) @ q.T
    np.testing.assert_allclose(rigid_body_share(t, position, component), 0.0, atol=1e-12)


def test_too_few_dofs_judge_nothing():
    """Three sensors along z on the y axis see two motions (z and the rotation about x): three
    DOFs are fewer than 2 x 2, so no share is given."""
    position = np.array([[0.0, y, 0.0] for y in range(3)], float)
    share = rigid_body_share(np.ones((2, 3)), position, [3, 3, 3])
    assert np.isnan(share).all()


@pytest.fixture(scope="module")
def hung_frame(tmp_path_factory):
    """The blind study's frame on soft grounded springs (x, y, z at the nose 1001 and the wing
    stations 2005 / 3005): its six lowest modes are the suspension. Returns its GVT (26 modes,
    5 % shape noise, positions from UFF-like coordinates) and the free frame's first elastic
    frequency."""
    folder = tmp_path_factory.mktemp("hung")
    free = frame.write_frame(folder)
    springs = [f"CELAS2  {9000 + 10 * i + c:<8d}{200.0:<8.1f}{g:<8d}{c:<8d}"
               for i, g in enumerate((1001, 2005, 3005)) for c in (1, 2, 3)]
    hung = folder / "hung.bdf"
    hung.write_text(free.read_text().replace("ENDDATA", "\n".join(springs) + "\nENDDATA"))
    model = read_model(hung)
    modes = compute_modes(model, 30)
    sensors = frame.sensors()
    key = {(int(g), int(c)): j for j, (g, c) in
           enumerate(zip(modes["grid"].values, modes["component"].values))}
    shape = modes["shape"].values[:26, [key[s] for s in sensors]]
    rng = np.random.default_rng(3)
    shape = shape + 0.05 * np.sqrt(np.mean(shape ** 2, axis=1, keepdims=True)) * \
        rng.standard_normal(shape.shape)
    xyz = dict(zip(model.grids.ids.tolist(), model.grids.xyz.tolist()))
    gvt = make_gvt_dataset(modes["frequency"].values[:26], shape, [g for g, _ in sensors],
                           [c for _, c in sensors], mode=np.arange(1, 27),
                           xyz=[xyz[g] for g, _ in sensors], source="hung frame", units="si")
    free_modes = compute_modes(read_model(free), 8)
    return gvt, float(free_modes["frequency"].values[elastic_index(free_modes)].min())


def test_the_hung_frame_has_six_suspension_modes(hung_frame):
    """Measured: suspension 0.09-0.21 Hz (first elastic 2.77 Hz), shares 0.997-0.998; the
    elastic modes' at most 0.25."""
    gvt, f1 = hung_frame
    f = gvt["frequency"].values
    assert f[5] < 0.5 * f[6]                                               # a soft suspension
    assert suspension_modes(gvt, f1).tolist() == [True] * 6 + [False] * 20
    assert not suspension_modes(gvt, 0.05).any()          # none below a first elastic of 0.05 Hz
    share = rigid_body_share(gvt["shape"].values,
                             np.stack([gvt[k].values for k in "xyz"], axis=1),
                             gvt["component"].values)
    assert share[:6].min() > 0.99 and share[6:].max() < RIGID_SHARE


def test_frequency_only_uses_the_first_elastic_frequency(hung_frame):
    """Without shapes: below half the free frame's first elastic frequency."""
    gvt, f1 = hung_frame
    bare = gvt.drop_vars("shape")
    assert suspension_modes(bare, f1).tolist() == [True] * 6 + [False] * 20


def test_without_positions_nothing_is_judged(hung_frame):
    gvt, f1 = hung_frame
    assert not suspension_modes(gvt.drop_vars(["x", "y", "z"]), f1).any()


def test_a_clamped_plate_bends_within_the_rigid_span(tmp_path):
    """Why only a free model is asked: the first bending mode of a cantilever plate (plate_decks,
    20 x 12, clamped at x = 0), read in z at every free grid, lies 90 % or more in the rigid-body
    span (z, and the rotation about y: w ~ x^2 is mostly a line over the plate)."""
    deck = plate_deck(tmp_path / "plate.bdf", nx=20, ny=12, boundary="cantilever", nmodes=4)
    model = read_model(deck)
    modes = compute_modes(model, 4)
    free = model.grids.xyz[:, 0] > 1e-9
    key = {(int(g), int(c)): j for j, (g, c) in
           enumerate(zip(modes["grid"].values, modes["component"].values))}
    cols = [key[(int(g), 3)] for g in model.grids.ids[free]]
    share = rigid_body_share(modes["shape"].values[:1, cols], model.grids.xyz[free],
                             np.full(int(free.sum()), 3))
    assert share[0] > RIGID_SHARE, share


def test_a_half_model_is_judged_by_its_own_rigid_body_motions(tmp_path):
    """The BAH wing (tests/data/bah_plane: the structure cards, SPC1 1246 at the root grid 1 as
    in its deck) moves as a rigid body in plunge and pitch only. Its first elastic mode, the
    symmetric wing bending with the fuselage mass (2.45 Hz), read in z at the other 19 grids and
    in x at seven wing grids, is nearly a roll at those sensors: its share of the six motions is
    above ``RIGID_SHARE`` (measured 0.94), of plunge and pitch far below (0.43). It is no
    suspension mode; a plunge-and-pitch motion at the same sensors is one."""
    inc = (DATA / "bah_plane" / "structure_bah.inc").read_text()
    deck = tmp_path / "bah.bdf"
    deck.write_text("SOL 103\nCEND\nSPC = 101\nMETHOD = 1\nBEGIN BULK\n" + inc
                    + "\nSPC1,101,1246,1\nEIGRL,1,,,8\nENDDATA\n")
    model = read_model(deck)
    modes = compute_modes(model, 8)
    assert modes["rigid_motion"].values[:2].tolist() != ["", ""]
    assert modes["rigid_motion"].values[2] == ""
    motions = model_motions(modes, model.grids.xyz[model.grids.index([1])[0]])
    assert motions.shape == (6, 2)
    # about the root grid: translations x, y and the rotations about x and z stay zero, plunge
    # and pitch only
    np.testing.assert_allclose(motions[[0, 1, 3, 5]], 0.0, atol=1e-9 * np.abs(motions).max())
    sensors = [(g, 3) for g in range(2, 21)] + [(g, 1) for g in range(7, 14)]
    key = {(int(g), int(c)): j for j, (g, c) in
           enumerate(zip(modes["grid"].values, modes["component"].values))}
    shape = modes["shape"].values[:3, [key[s] for s in sensors]]
    shape[0] = shape[0] + 0.3 * shape[1]                       # a suspension mode: plunge + pitch
    xyz = dict(zip(model.grids.ids.tolist(), model.grids.xyz.tolist()))
    position = np.array([xyz[g] for g, _ in sensors])
    component = np.array([c for _, c in sensors])
    six = rigid_body_share(shape, position, component)
    own = rigid_body_share(shape, position, component,
                           model_motions(modes, position.mean(axis=0)))
    assert six[2] > RIGID_SHARE and own[2] < 0.5, (six, own)
    np.testing.assert_allclose(own[:2], 1.0, rtol=1e-9)
    f = np.array([0.4, 0.6, float(modes["frequency"].values[2])])
    gvt = make_gvt_dataset(f, shape, [g for g, _ in sensors], component, mode=[1, 2, 3],
                           xyz=position, source="bah", units="si")
    kept, hung = without_suspension(modes, gvt)
    assert hung["mode"].values.tolist() == [1, 2] and kept["mode"].values.tolist() == [3]


@pytest.mark.skipif(mystran_executable() is None, reason="mystran is not installed")
@pytest.mark.parametrize("half", [False, True])
def test_a_grid_only_rods_reach_keeps_the_rigid_body_motions(tmp_path, half):
    """The BAH wing free-free (and as the half model) with a grid on three CRODs: AUTOSPC holds
    that grid's rotations, which a rigid rotation would turn. compute_modes took the rigid-body
    modes for a mechanism (its check compared those DOFs too) and model_motions found no rigid
    motion fitting them. Independent reference: MYSTRAN (its RBAR written as the RBE2 it is),
    measured equal to 1e-4 Hz in the 8 elastic modes; the motions are six, or plunge and pitch."""
    inc = re.sub(r"RBAR, *(\d+), *(\d+), *(\d+), *123456", r"RBE2,\1,\2,123456,\3",
                 (DATA / "bah_plane" / "structure_bah.inc").read_text())
    rods = ("GRID,30,,1.,6.,1.\nCROD,901,902,4,30\nCROD,902,902,9,30\nCROD,903,902,3,30\n"
            "PROD,902,501,1.e-3\n")
    spc = ("SPC = 101\n", "SPC1,101,1246,1\n") if half else ("", "")
    deck = tmp_path / "bah.bdf"
    deck.write_text(f"SOL 103\nCEND\n{spc[0]}METHOD = 1\nBEGIN BULK\n{inc}\n{spc[1]}"
                    f"EIGRL,1,,,14\n{rods}ENDDATA\n")
    model = read_model(deck)
    ours = compute_modes(model, 14)
    n_rigid = 2 if half else 6
    assert int(ours.attrs["rigid_modes"]) == n_rigid
    motions = model_motions(ours, model.grids.xyz.mean(axis=0))
    assert motions.shape == (6, n_rigid) and np.linalg.matrix_rank(motions) == n_rigid
    theirs = mystran_modes(deck, 14)
    np.testing.assert_allclose(ours["frequency"].values[n_rigid:14],
                               theirs["frequency"].values[n_rigid:14], rtol=1e-4)
