"""Mirror-image pairs of candidates: a pair keeps a symmetric model symmetric (every grid keeps
its image, every mode is symmetric or antisymmetric), one side or a wrong sign does not."""
from dataclasses import replace

import numpy as np
import pytest

from pipeline.diagnose.apply import apply_effect
from pipeline.diagnose.effects import candidates
from pipeline.diagnose.mirror import mirror_grids, mirror_pairs, sites
from structures.massprops import mass_properties
from structures.modal import compute_modes

#: Reflection y -> -y of a displacement: translations (components 1-3) as a vector, rotations
#: (4-6) as a pseudo-vector (det R R).
COMPONENT_SIGN = {1: 1.0, 2: -1.0, 3: 1.0, 4: -1.0, 5: 1.0, 6: -1.0}


@pytest.fixture(scope="module")
def x56_pairs(x56):
    return [c for c in candidates(x56) if c.get("sites") is not None]


def _reflection_cosines(model, n=24):
    """|phi . R phi| / (|phi| |R phi|) of every elastic mode over the grids that have a mirror
    image (1 for a symmetric or antisymmetric mode), and whether every grid has one."""
    image = mirror_grids(model)
    ds = compute_modes(model, n)
    grid, comp = ds["grid"].values, ds["component"].values
    row = {(int(g), int(c)): i for i, (g, c) in enumerate(zip(grid, comp))}
    mapped = np.array([int(g) in image for g in grid])
    rows = np.array([row[(image[int(g)], int(c))] for g, c in zip(grid[mapped], comp[mapped])])
    sign = np.array([COMPONENT_SIGN[int(c)] for c in comp[mapped]])
    phi = ds["shape"].values[:, mapped]
    twin = ds["shape"].values[:, rows] * sign
    cos = np.abs(np.sum(phi * twin, axis=1)) / np.sqrt(np.sum(phi ** 2, axis=1)
                                                        * np.sum(twin ** 2, axis=1))
    return cos[ds["rigid_motion"].values == ""], len(image) == len(model.grids)


def test_the_example_is_its_own_mirror_image(x56):
    image = mirror_grids(x56)
    assert len(image) == len(x56.grids)
    assert image[3009] == 4009 and image[4009] == 3009 and image[1001] == 1001
    # its lowest 18 elastic modes are 2e-4 or more apart: symmetric or antisymmetric each
    cos, whole = _reflection_cosines(x56)
    assert whole and cos.min() > 1.0 - 1e-9


@pytest.mark.parametrize("kind, label", [
    ("lumped_mass", "grid 3009 "), ("joint_flexibility", "RBE2 7501"),
    ("member_taper", "PID 111"), ("member_curvature", "PID 111 (CBAR 3001, grids 3001-3002) bow +y -z"),
    ("member_curvature", "PID 103 (CBAR 6100, grids 2001-6101) bow +y +z"),
    ("boundary_stiffness", "grid 3005 z")])
def test_a_pair_keeps_the_model_symmetric_and_one_side_does_not(x56, x56_pairs, kind, label):
    pair = next(c for c in x56_pairs if c.kind == kind and c.label.startswith(label) or
                c.kind == kind and kind.startswith("member") and label in c.label)
    values = np.array(pair.reference) * 2.0
    both, whole = _reflection_cosines(apply_effect(x56, pair, values))
    # a hung joint adds a grid coincident with its independent grid: coincident grids have no
    # certain image, so the cosines are over the other grids
    assert (whole or kind == "joint_flexibility") and both.min() > 1.0 - 1e-8
    one, _ = _reflection_cosines(apply_effect(x56, sites(pair)[0], values))
    assert one.min() < 1.0 - 1e-6      # over the grids both share (measured 0.9994 or less)
    assert set(pair.location.grids) == set(sites(pair)[0].location.grids) | set(
        sites(pair)[1].location.grids)


@pytest.mark.parametrize("label, k", [("PID 111 (CBAR 3001, grids 3001-3002) bow +y -z", 1),
                                      ("PID 103 (CBAR 6100, grids 2001-6101) bow +y +z", 0),
                                      ("PID 103 (CBAR 6100, grids 2001-6101) bow +y +z", 1)])
def test_a_bow_of_the_wrong_sign_on_the_image_breaks_the_symmetry(x56, x56_pairs, label, k):
    pair = next(c for c in x56_pairs if c.kind == "member_curvature" and label in c.label)
    own, twin = pair.get("signs")
    wrong = list(twin)
    wrong[k] = -wrong[k]
    detail = tuple((key, v) for key, v in pair.detail if key != "signs")
    bad = replace(pair, detail=detail + (("signs", (own, tuple(wrong))),))
    cos, whole = _reflection_cosines(apply_effect(x56, bad, 2.0 * np.array(pair.reference)))
    assert not whole and cos.min() < 1.0 - 1e-6


def test_a_taper_runs_the_mirror_way_on_the_image(x56, x56_pairs):
    pair = next(c for c in x56_pairs if c.kind == "member_taper" and "PID 111" in c.label)
    own, twin = pair.get("signs")
    detail = tuple((key, v) for key, v in pair.detail if key != "signs")
    bad = replace(pair, detail=detail + (("signs", (own, (twin[0], -twin[1]))),))
    assert _reflection_cosines(apply_effect(x56, pair, [0.2, 0.6]))[0].min() > 1.0 - 1e-8
    assert _reflection_cosines(apply_effect(x56, bad, [0.2, 0.6]))[0].min() < 1.0 - 1e-6


def test_a_mass_pair_adds_twice_the_mass_and_keeps_the_cg_on_the_plane(x56, x56_pairs):
    pair = next(c for c in x56_pairs if c.kind == "lumped_mass" and c.label.startswith("grid 3009"))
    before, after = mass_properties(x56), mass_properties(apply_effect(x56, pair, [0.01, 0.0]))
    assert after.weight == pytest.approx(before.weight + 2 * 0.01 * pair.get("total_mass"), rel=1e-12)
    assert abs(after.cg[1] - before.cg[1]) <= 1e-9 * abs(after.cg).max()


def test_each_pair_once_of_two_distinct_whole_sites(x56, x56_pairs):
    keys = [(c.kind, c.location, c.parameters, c.lower, c.upper) for c in x56_pairs]
    assert len(keys) == len(set(keys))
    assert not any(c.get("dependent") is not None for c in x56_pairs)
    for pair in x56_pairs:
        a, b = sites(pair)
        assert set(a.location.grids).isdisjoint(b.location.grids) or pair.kind.startswith("member")
        assert set(a.location.grids) != set(b.location.grids)


def test_coincident_grids_have_no_image_and_the_plane_is_its_own(x56):
    xyz = np.vstack([x56.grids.xyz, x56.grids.xyz[x56.grids.index([3009])]])
    n = len(x56.grids)
    grids = replace(x56.grids, ids=np.append(x56.grids.ids, 99999), xyz=xyz,
                    cd_axes=np.concatenate([x56.grids.cd_axes, x56.grids.cd_axes[:1]]),
                    cd=np.append(x56.grids.cd, 0), ps=np.append(x56.grids.ps, 0))
    image = mirror_grids(replace(x56, grids=grids))
    assert len(x56.grids) == n and 99999 not in image and 3009 not in image and 4009 not in image
    assert image[1001] == 1001 and image[3008] == 4008


def test_an_asymmetric_model_has_no_pairs(x56):
    moved = x56.grids.xyz.copy()
    moved[:, 1] += 0.37 * moved[:, 0] / np.ptp(moved[:, 0])            # a sheared model
    sheared = replace(x56, grids=replace(x56.grids, xyz=moved))
    assert not any(c.get("sites") for c in candidates(sheared, ("lumped_mass",)))
    assert mirror_pairs(x56, candidates(x56, ("lumped_mass",))) != ()
