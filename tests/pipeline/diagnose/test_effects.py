"""The candidate-effect library of diagnose (pipeline.diagnose.effects): the candidates of the
example, their neighbours, bad kinds and values, and the directional joint."""
import numpy as np
import pytest

from pipeline.diagnose.apply import apply_effect
from pipeline.diagnose.effects import KINDS, Candidate, Location, candidates, neighbours
from pipeline.diagnose.mirror import mirror_grids
from pipeline.diagnose.members import find_members
from structures.assembly import assemble_g
from structures.bdf import read_model
from structures.common.errors import InputError
from structures.modal import compute_modes
from tests.pipeline.diagnose.small_decks import hinge_deck, pick


# --------------------------------------------------------------------------- library & errors
def test_candidates_of_x56_and_neighbours(x56, x56_candidates):
    one_sided = [c for c in x56_candidates if c.get("sites") is None]
    counts = {k: sum(c.kind == k for c in one_sided) for k in KINDS}
    # 28 RBE2 in structure_x56.inc, 26 of them with two dependent grids (one-sided variants)
    assert counts["joint_flexibility"] == 28 + 2 * 26
    # every grid carries structure, none fixed: a point mass at each, and a spread mass over
    # each distinct set of a grid and its neighbours (neighbours(): one element layer)
    points = [c for c in one_sided if c.kind == "lumped_mass" and len(c.location.grids) == 1]
    assert len(points) == len(x56.grids)
    grown = {neighbours(x56, Location(grids=(g,))).grids for g in x56.grids.ids.tolist()}
    spreads = {c.location.grids for c in one_sided
               if c.kind == "lumped_mass" and len(c.location.grids) > 1}
    assert spreads == {g for g in grown if len(g) > 1}
    assert counts["lumped_mass"] == len(x56.grids) + len(spreads)
    assert pick(x56_candidates, "lumped_mass", "grid 5111 spread over 5101, 5121"
                 ).location.grids == (5101, 5111, 5121)      # pylon base and top, engine
    assert counts["boundary_stiffness"] == 3 * len(x56.grids)
    assert counts["member_taper"] == counts["member_curvature"] / 4 == len(find_members(x56))
    # mirror pairs (pipeline.diagnose.mirror): 92 of the 103 grids lie off the plane y = 0, the
    # 28 RBE2 are 14 left / right pairs, 16 members have a mirror image (four bow quadrants each;
    # two of them, PID 101 from grid 1006 and PID 103 from grid 1004, meet it on the plane), and
    # a spread mass has one when its image grids are another spread's sharing no grid with it
    pairs = {k: sum(c.kind == k and c.get("sites") is not None for c in x56_candidates)
             for k in KINDS}
    off_plane = int(np.sum(np.abs(x56.grids.xyz[:, 1]) > 1e-9))
    assert off_plane == 92
    image = mirror_grids(x56)
    twins = {g for g in spreads if tuple(sorted(image[i] for i in g)) in spreads - {g}
             and not set(g) & {image[i] for i in g}}          # spreads meeting on the plane
    assert pairs == {"lumped_mass": off_plane // 2 + len(twins) // 2,
                     "boundary_stiffness": 3 * off_plane // 2,
                     "joint_flexibility": 14, "member_taper": 16, "member_curvature": 64}
    grown = neighbours(x56, Location(grids=(3005,)))
    assert grown.grids == (3004, 3005, 3006, 3105, 3205)
    assert grown.elements == (3004, 3005, 7005)
    assert grown.properties == (114, 115)
    bar = neighbours(x56, Location(elements=(3005,)))      # CBAR 3005: grids 3005-3006
    assert bar.elements == (3004, 3005, 3006, 7005, 7006)
    assert bar.grids == (3004, 3005, 3006, 3007, 3105, 3106, 3205, 3206)


def test_bad_kinds_and_values_raise(x56, x56_candidates):
    with pytest.raises(InputError, match="lumped_mass"):
        candidates(x56, ["cable_mass"])
    with pytest.raises(InputError):
        Candidate("cable_mass", Location(grids=(1,)), "x", ("m",), (0.0,), (1.0,), (0.1,))
    with pytest.raises(InputError, match="bounds"):
        Candidate("lumped_mass", Location(grids=(1,)), "x", ("mass",), (0.1,), (1.0,), (0.2,))
    with pytest.raises(InputError, match=r"'PID 7 bow \+y -z': reference 0 for \['bow_2'\]"):
        Candidate("member_curvature", Location(properties=(7,)), "PID 7 bow +y -z",
                  ("bow_1", "bow_2"), (0.0, -0.15), (0.15, 0.0), (0.05, 0.0))
    bare = Candidate("boundary_stiffness", Location(grids=(3005,)), "grid 3005 z", ("k_z",),
                     (0.0,), (1.0,), (0.1,))
    with pytest.raises(InputError, match="candidates"):
        apply_effect(x56, bare, [0.1])
    cand = pick(x56_candidates, "lumped_mass", "grid 3005")
    for bad in ([0.5], [-0.01], [np.nan], [0.01, 0.02]):
        with pytest.raises(InputError, match="grid 3005"):
            apply_effect(x56, cand, bad)


def test_directional_joint_by_hand(tmp_path):
    """The one-dependent hinge of test_one_dependent_grid_on_its_spring (grid 3, mass m3 and
    inertia i3, coincident with grid 1) in its directional form: :func:`directional` of (c, rho)
    gives c_t c_t c_t c_r c_r c_r and the same K; then one compliance per component, the modes
    are by hand sqrt(k_t / (c_p m3)) for the translations and sqrt(k_r / (c_p i3)) for the
    rotations, each component's own; a mix of zero and nonzero compliances is refused."""
    from pipeline.diagnose.effects import JOINT_DIRECTIONS, directional

    m3, i3 = 2.0, 0.01
    model = read_model(hinge_deck(tmp_path, 5.0, m3, i3))
    cand = pick(candidates(model, ["joint_flexibility"]), "joint_flexibility", "(1-3 only)")
    kt, kr = cand.get("k_translation"), cand.get("k_rotation")
    rich, values = directional(cand, [300.0, 0.8])
    assert rich.parameters == JOINT_DIRECTIONS
    np.testing.assert_allclose(values, [300.0 / 10 ** 0.4] * 3 + [300.0 * 10 ** 0.4] * 3,
                               rtol=1e-12)
    for got, want in zip(assemble_g(apply_effect(model, rich, values)),
                         assemble_g(apply_effect(model, cand, [300.0, 0.8]))):
        assert abs(got - want).max() <= 1e-12 * abs(want).max()
    c = np.array([100.0, 400.0, 1600.0, 50.0, 200.0, 3200.0])
    f = np.sort(compute_modes(apply_effect(model, rich, c), 6)["frequency"].values)
    expected = np.sort(np.sqrt(np.r_[kt / (c[:3] * m3), kr / (c[3:] * i3)]) / (2 * np.pi))
    np.testing.assert_allclose(f, expected, rtol=1e-8)
    with pytest.raises(InputError, match="mix zero"):
        apply_effect(model, rich, [0.0, 1.0, 1.0, 1.0, 1.0, 1.0])
    with pytest.raises(InputError, match="no directional form"):
        directional(rich, c)


def test_directional_mirror_pair_of_engine_mounts(x56, x56_candidates):
    """The engine mounts' mirror pair (RBE2 7501 and its image) in directional form: both sites
    take the pair's six compliances (the images' signs all +1: a CBUSH's diagonal stiffness in
    basic axes mirrors onto itself about the XZ plane), the model is the two-parameter pair's at
    the matching values, and the JSON names six parameters per site."""
    from pipeline.diagnose.effects import JOINT_DIRECTIONS, directional
    from pipeline.diagnose.result import EffectRecord, effect_json

    pair = next(c for c in x56_candidates if c.kind == "joint_flexibility"
                and c.get("sites") is not None and 7501 in c.location.elements)
    rich, values = directional(pair, [300.0, -0.6])
    for got, want in zip(assemble_g(apply_effect(x56, rich, values)),
                         assemble_g(apply_effect(x56, pair, [300.0, -0.6]))):
        assert abs(got - want).max() <= 1e-12 * abs(want).max()
    record = effect_json(EffectRecord(rich, values * np.arange(1, 7), 0.0))
    assert [list(s["parameters"]) for s in record["sites"]] == [list(JOINT_DIRECTIONS)] * 2
    assert [list(s["parameters"].values()) for s in record["sites"]] == \
        [list(values * np.arange(1, 7))] * 2
