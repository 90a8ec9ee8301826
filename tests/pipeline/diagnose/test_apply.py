"""Adding a candidate effect to a model (pipeline.diagnose.apply): analytic spring-mass and
beam references, hand computations, the rigid-joint limit and the change matrices."""
from dataclasses import replace

import numpy as np
import pytest
import scipy.sparse.linalg as spla
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from pipeline.diagnose.apply import apply_effect, effect_matrices, write_effect_deck
from pipeline.diagnose.effects import KINDS, candidates
from pipeline.diagnose.members import find_members
from structures.assembly import assemble, assemble_g
from structures.bdf import read_model
from structures.common.errors import InputError
from structures.massprops import mass_properties
from structures.modal import compute_modes
from tests.pipeline.diagnose.small_decks import (elastic, hinge_deck, pick, quadratic_frequencies,
                                                 small_deck)


# --------------------------------------------------------------------------- spring-mass decks
def test_lumped_mass_on_one_and_two_dof_spring_mass(tmp_path):
    k1, k2, m1, m2 = 4.0e3, 2.5e3, 2.0, 3.0
    one = read_model(small_deck(tmp_path, "one.bdf", [
        ("GRID", 1, None, 0.0, 0.0, 0.0, None, 12456), ("CELAS2", 11, k1, 1, 3),
        ("CONM2", 21, 1, None, m1)]))
    cand = pick(candidates(one, ["lumped_mass"]), "lumped_mass", "grid 1")
    f = elastic(apply_effect(one, cand, [0.05, 0.0]), 1)
    assert f[0] == pytest.approx(np.sqrt(k1 / (1.05 * m1)) / (2 * np.pi), rel=1e-10)

    two = read_model(small_deck(tmp_path, "two.bdf", [
        ("GRID", 1, None, 0.0, 0.0, 0.0, None, 12456),
        ("GRID", 2, None, 1.0, 0.0, 0.0, None, 12456),
        ("CELAS2", 11, k1, 1, 3), ("CELAS2", 12, k2, 1, 3, 2, 3),
        ("CONM2", 21, 1, None, m1), ("CONM2", 22, 2, None, m2)]))
    cand = pick(candidates(two, ["lumped_mass"]), "lumped_mass", "grid 2")
    p = 0.08
    f = elastic(apply_effect(two, cand, [p, 0.0]), 2)
    expected = quadratic_frequencies([[k1 + k2, -k2], [-k2, k2]], [m1, m2 + p * (m1 + m2)])
    np.testing.assert_allclose(f, expected, rtol=1e-10)


def test_lumped_mass_inertia_on_a_torsion_spring(tmp_path):
    """Grid 1 moves along x on a spring k_x and turns about x on a torsion spring k (CELAS2 on
    components 1 and 4) and carries a CONM2 of mass m and I11 = i; a clamped grid 2 at distance
    2 makes the model's size L = 2. A mass p m with inertia q adds p m q L^2 about each axis: by
    hand the modes are sqrt(k_x / ((1 + p) m)) / 2 pi and sqrt(k / (i + p m q L^2)) / 2 pi."""
    k_x, k, m, i, p, q = 5.0e3, 3.0e3, 4.0, 0.5, 0.05, 4e-3
    model = read_model(small_deck(tmp_path, "torsion.bdf", [
        ("GRID", 1, None, 0.0, 0.0, 0.0, None, 2356),
        ("GRID", 2, None, 2.0, 0.0, 0.0, None, 123456), ("CELAS2", 11, k, 1, 4),
        ("CELAS2", 12, k_x, 1, 1),
        ("CONM2", 21, 1, None, m, 0.0, 0.0, 0.0, None, i, 0.0, i, 0.0, 0.0, i)]))
    cand = pick(candidates(model, ["lumped_mass"]), "lumped_mass", "grid 1")
    f = compute_modes(apply_effect(model, cand, [p, q]), 2)["frequency"].values
    expected = [np.sqrt(k_x / ((1 + p) * m)), np.sqrt(k / (i + p * m * q * 2.0 ** 2))]
    np.testing.assert_allclose(np.sort(f), np.sort(expected) / (2 * np.pi), rtol=1e-10)


def test_grounded_spring_on_free_free_two_masses(tmp_path):
    k, m1, m2 = 1.0e4, 2.0, 5.0
    model = read_model(small_deck(tmp_path, "free.bdf", [
        ("GRID", 1, None, 0.0, 0.0, 0.0, None, 12456),
        ("GRID", 2, None, 1.0, 0.0, 0.0, None, 12456),
        ("CELAS2", 12, k, 1, 3, 2, 3), ("CONM2", 21, 1, None, m1), ("CONM2", 22, 2, None, m2)]))
    f_elastic = np.sqrt(k * (m1 + m2) / (m1 * m2)) / (2 * np.pi)
    assert elastic(model, 2)[0] == pytest.approx(f_elastic, rel=1e-10)
    cands = candidates(model, ["boundary_stiffness"])
    assert sorted(c.label for c in cands) == ["grid 1 z", "grid 2 z"]   # x, y fixed by PS
    p = 0.3
    k_ground = p * (m1 + m2) * (2 * np.pi * f_elastic) ** 2    # the documented scale
    f = compute_modes(apply_effect(model, pick(cands, "boundary_stiffness", "grid 1 z"), [p]),
                      2)["frequency"].values
    np.testing.assert_allclose(f, quadratic_frequencies([[k + k_ground, -k], [-k, k]], [m1, m2]),
                               rtol=1e-9)


def test_total_mass_and_cg_follow_the_added_mass(x56, x56_candidates):
    before = mass_properties(x56)
    cand = pick(x56_candidates, "lumped_mass", "grid 3005")
    p = 0.037
    after = mass_properties(apply_effect(x56, cand, [p, 0.0]))
    assert after.mass - before.mass == pytest.approx(p * before.mass, rel=1e-12)
    x_grid = x56.grids.xyz[x56.grids.index([3005])[0]]
    np.testing.assert_allclose(after.cg, (before.cg + p * x_grid) / (1 + p), rtol=1e-12)
    # spread in equal shares over the pylon base, its top and the engine: the CG moves towards
    # the three grids' centroid, and each carries a third of the mass
    spread = pick(x56_candidates, "lumped_mass", "grid 5111 spread over 5101, 5121")
    model = apply_effect(x56, spread, [p, 0.0])
    after = mass_properties(model)
    assert after.mass - before.mass == pytest.approx(p * before.mass, rel=1e-12)
    centroid = x56.grids.xyz[x56.grids.index([5101, 5111, 5121])].mean(axis=0)
    np.testing.assert_allclose(after.cg, (before.cg + p * centroid) / (1 + p), rtol=1e-12)
    added = model.masses.mass[len(x56.masses.mass):]
    assert model.masses.grid[len(x56.masses.mass):].tolist() == [5101, 5111, 5121]
    np.testing.assert_allclose(added, p * before.weight / 3, rtol=1e-12)


# ------------------------------------------------------------------------------------ members
def test_members_of_x56(x56):
    members = {(m.pid, m.eids[0]): m for m in find_members(x56)}
    fuselage = members[(101, 1003)]
    # PID 101: the fuselage 1001..1007 runs straight through grid 1006, where the two pylon
    # elements (also PID 101) branch off and are members of their own.
    assert fuselage.grids == (1001, 1002, 1003, 1004, 1005, 1006, 1007)
    assert fuselage.eids == (1003, 1004, 1005, 1006, 1007, 1008)
    assert fuselage.length == pytest.approx(72.0)
    np.testing.assert_allclose(fuselage.xi_mid, (np.arange(6) + 0.5) / 6)
    assert members[(101, 5001)].grids == (1006, 5001)
    assert members[(102, 1002)].grids == (1001, 1102, 1101)


def test_taper_copies_a_shared_property(x56, x56_candidates):
    cand = pick(x56_candidates, "member_taper", "PID 101 (CBAR 1003")
    new = apply_effect(x56, cand, [0.1, 0.5])
    es = new.elements["CBAR"]
    pids = dict(zip(es.eids.tolist(), es.pids.tolist()))
    assert pids[5001] == pids[5101] == 101 and new.properties[101] == x56.properties[101]
    # the six fuselage elements are split in 2 (12 pieces: MIN_SEGMENTS 8), at new grids on
    # their line (the deck's largest grid is 6203), and the pieces get PIDs 253..264 (the deck's
    # largest PID is 252), in chain order
    assert max(x56.grids.ids) == 6203 and new.grids.ids[-6:].tolist() == list(range(6204, 6210))
    xyz = dict(zip(x56.grids.ids.tolist(), x56.grids.xyz))
    np.testing.assert_allclose(new.grids.xyz[-6:], [(xyz[g] + xyz[g + 1]) / 2
                                                    for g in range(1001, 1007)], atol=1e-12)
    fuselage = [e for e in es.eids.tolist() if e in (1003, 1004, 1005, 1006, 1007, 1008)
                or e > max(x56.elements["CBAR"].eids)]
    fresh = sorted(pids[e] for e in fuselage)
    assert max(x56.properties) == 252 and fresh == list(range(253, 265))
    # by hand: PBAR 101 is A 6, I1 60, I2 40, I12 0, J 60; xi_mid = 1/24, 3/24, .., 23/24 gives
    # s = 1.1 (1 + 0.5 (xi - 1/2)) = 1.1 x 37/48, 39/48, .., 59/48; A 6 s^2, I s^4
    s = 1.1 * (37.0 + 2.0 * np.arange(12)) / 48.0
    hand = {"A": 6.0 * s ** 2, "I1": 60.0 * s ** 4, "I2": 40.0 * s ** 4, "J": 60.0 * s ** 4,
            "I12": np.zeros(12)}
    assert hand["A"][0] == pytest.approx(4.31377604167, rel=1e-10)      # 7.26 x 1369 / 2304
    for key, values in hand.items():
        np.testing.assert_allclose([new.properties[p].fields[key] for p in fresh], values,
                                   rtol=1e-14, atol=0.0, err_msg=key)
    assert all(new.properties[p].fields["MID"] == 1 and new.properties[p].card == "PBAR"
               for p in fresh)
    again = apply_effect(new, cand, [0.1, 0.0])                # a second taper multiplies
    es2 = again.elements["CBAR"]
    assert es2.pids.tolist() == es.pids.tolist()              # the copies are now the only users
    assert len(again.grids) == len(new.grids)                 # and the pieces are kept
    np.testing.assert_allclose([again.properties[p].fields["A"] for p in fresh],
                               1.21 * 6.0 * s ** 2, rtol=1e-14)       # A ~ 1.1^2 once more


def _cantilever(tmp_path, n, length, props):
    """n CBARs of one PID; I2 = J = 100 I1, so the two lowest modes bend in plane 1."""
    e_mod, rho, area, inertia = props
    cards = [("GRID", i + 1, None, length * i / n, 0.0, 0.0, None, 123456 if i == 0 else None)
             for i in range(n + 1)]
    cards += [("CBAR", 100 + i, 7, i + 1, i + 2, 0.0, 1.0, 0.0) for i in range(n)]
    cards += [("PBAR", 7, 1, area, inertia, 100 * inertia, 100 * inertia),
              ("MAT1", 1, e_mod, None, 0.3, rho)]
    return read_model(small_deck(tmp_path, f"cantilever{n}.bdf", cards, ["PARAM,COUPMASS,1"]))


def _tapered_cantilever_frequencies(length, props, taper, count):
    """Shooting on (E I w'')'' = rho A omega^2 w, clamped at x = 0, free at x = L, with
    A ~ s^2, I ~ s^4, s = 1 + taper (x / L - 1/2): an independent continuous reference."""
    e_mod, rho, area, inertia = props

    def tip(omega):
        def rhs(x, y):
            s = 1 + taper * (x / length - 0.5)
            ei, ra = e_mod * inertia * s ** 4, rho * area * s ** 2
            w, dw, moment, shear = y
            return [dw, moment / ei, shear, ra * omega ** 2 * w]
        ends = [solve_ivp(rhs, (0, length), y0, rtol=1e-10, atol=1e-13).y[2:, -1]
                for y0 in ([0, 0, 1, 0], [0, 0, 0, 1])]
        return np.linalg.det(np.array(ends).T)

    omega_1 = 1.8751 ** 2 * np.sqrt(e_mod * inertia / (rho * area)) / length ** 2
    grid = omega_1 * np.linspace(0.3, 10.0, 60)
    values = [tip(w) for w in grid]
    roots = [brentq(tip, a, b) for a, b, fa, fb in zip(grid, grid[1:], values, values[1:])
             if fa * fb < 0]
    return np.array(roots[:count]) / (2 * np.pi)


def test_tapered_cantilever_against_the_continuous_beam(tmp_path):
    length, props = 10.0, (1.0e3, 1.0, 1.0, 0.005)
    model = _cantilever(tmp_path, 40, length, props)
    cand = pick(candidates(model, ["member_taper"]), "member_taper")
    assert cand.parameters == ("scale", "taper")
    taper = 0.6
    bending = compute_modes(apply_effect(model, cand, [0.0, taper]), 2)["frequency"].values
    reference = _tapered_cantilever_frequencies(length, props, taper, 2)
    np.testing.assert_allclose(bending, reference, rtol=2e-3)
    uniform = _tapered_cantilever_frequencies(length, props, 0.0, 1)[0]
    assert bending[0] / uniform == pytest.approx(reference[0] / uniform, rel=2e-3)
    assert abs(bending[0] / uniform - 1) > 0.05      # the taper is clearly visible


def _one_bar(tmp_path, length, area, i1, i2):
    """One CBAR along x from grid 1 (clamped) to grid 2, plane 1 = x-y."""
    return read_model(small_deck(tmp_path, "one_bar.bdf", [
        ("GRID", 1, None, 0.0, 0.0, 0.0, None, 123456), ("GRID", 2, None, length, 0.0, 0.0),
        ("CBAR", 10, 7, 1, 2, 0.0, 1.0, 0.0), ("PBAR", 7, 1, area, i1, i2, 1.0),
        ("MAT1", 1, 2.0e5, None, 0.3, 0.0)]))


def _tip_displacement(model, component, load):
    system = assemble(model)
    force = np.zeros(system.K.shape[0])
    force[np.flatnonzero(system.a_dofs == 6 * 1 + component)] = load
    return system.T @ spla.spsolve(system.K.tocsc(), force)


def test_bowed_one_element_member_by_the_unit_load_method(tmp_path):
    """A one-element member bowed by b in plane 1 becomes 8 chords of the parabola
    y = 4 b L xi (1 - xi) through 7 new grids. Axial P at the free end, by virtual work on the
    chords (N = P cos a, M = P y; unit loads n = cos a / sin a, m = y / (L - x)):
    u_x = sum P cos^2 a l / EA + P l (y1^2 + y1 y2 + y2^2) / 3 E I1 and
    u_y = sum P cos a sin a l / EA + P l (2 y1 m1 + y1 m2 + y2 m1 + 2 y2 m2) / 6 E I1."""
    e_mod, area, i1, i2, length, p, bow = 2.0e5, 3.0, 0.7, 1.3, 4.0, 10.0, 0.05
    model = _one_bar(tmp_path, length, area, i1, i2)
    cand = pick(candidates(model, ["member_curvature"]), "member_curvature")
    bowed = apply_effect(model, cand, [bow, 0.0])
    xs = np.linspace(0.0, length, 9)
    ys = 4.0 * bow * length * xs / length * (1.0 - xs / length)       # 0, 0.0875, .., 0.2, .., 0
    assert bowed.grids.ids.tolist() == list(range(1, 10))
    np.testing.assert_allclose(bowed.grids.xyz[2:, :2], np.column_stack([xs, ys])[1:8],
                               atol=1e-15)
    assert bowed.elements["CBAR"].nodes.tolist() == [[1, 3], [3, 4], [4, 5], [5, 6], [6, 7],
                                                     [7, 8], [8, 9], [9, 2]]
    ux = uy = 0.0
    for k in range(8):
        dx, dy = xs[k + 1] - xs[k], ys[k + 1] - ys[k]
        chord = np.hypot(dx, dy)
        cos, sin = dx / chord, dy / chord
        (y1, y2), (m1, m2) = ys[k:k + 2], length - xs[k:k + 2]
        ux += p * cos ** 2 * chord / (e_mod * area) + \
            p * chord * (y1 * y1 + y1 * y2 + y2 * y2) / (3.0 * e_mod * i1)
        uy += p * cos * sin * chord / (e_mod * area) + \
            p * chord * (2 * y1 * m1 + y1 * m2 + y2 * m1 + 2 * y2 * m2) / (6.0 * e_mod * i1)
    u = _tip_displacement(bowed, 0, p)
    np.testing.assert_allclose(u[6:8], [ux, uy], rtol=1e-9)
    straight = p * length / (e_mod * area)
    assert u[6] / straight > 1.07                  # the bow softens the member's axial load path


def test_one_element_taper_is_resolved_by_eight_pieces(tmp_path):
    """A one-element cantilever tapered by t: 8 uniform pieces with I(xi_k) = I (1 + t (xi_k -
    1/2))^4 at their mid-lengths xi_k = 1/16 .. 15/16; tip load P: w = sum P int (L - x)^2 dx /
    E I_k by hand, within 2 % of the continuous taper's P int (L - x)^2 / E I(x) dx."""
    e_mod, area, i1, length, p, taper = 2.0e5, 3.0, 0.7, 4.0, 10.0, 0.6
    model = _one_bar(tmp_path, length, area, i1, 100.0 * i1)
    cand = pick(candidates(model, ["member_taper"]), "member_taper")
    assert cand.parameters == ("scale", "taper")
    tapered = apply_effect(model, cand, [0.0, taper])
    xi = (np.arange(8) + 0.5) / 8
    inertia = i1 * (1.0 + taper * (xi - 0.5)) ** 4
    edges = length * np.arange(9) / 8
    hand = np.sum(p * ((length - edges[:-1]) ** 3 - (length - edges[1:]) ** 3)
                  / (3.0 * e_mod * inertia))
    w = _tip_displacement(tapered, 1, p)[7]
    assert w == pytest.approx(hand, rel=1e-9)
    x = np.linspace(0.0, length, 4001)
    f = (length - x) ** 2 / (e_mod * i1 * (1.0 + taper * (x / length - 0.5)) ** 4)
    continuous = p * np.sum((f[1:] + f[:-1]) / 2 * np.diff(x))
    assert w == pytest.approx(continuous, rel=0.02)
    assert abs(w / (p * length ** 3 / (3 * e_mod * i1)) - 1) > 0.2     # the taper is visible


def test_a_split_member_keeps_its_pieces_and_bows_add(tmp_path):
    """Taper then curvature on one split member: the pieces keep their tapered PIDs and the
    new grids move onto the arc; two bows b1, b2 give the arc of b1 + b2."""
    model = _one_bar(tmp_path, 4.0, 3.0, 0.7, 1.3)
    taper, up, bow = candidates(model, ["member_taper", "member_curvature"])[:3]
    assert (up.lower, up.upper, bow.lower, bow.upper) == ((0.0, 0.0), (0.15, 0.15),
                                                          (0.0, -0.15), (0.15, 0.0))
    tapered = apply_effect(model, taper, [0.1, 0.2])
    both = apply_effect(tapered, bow, [0.05, 0.0])
    assert both.grids.ids.tolist() == tapered.grids.ids.tolist()
    assert both.elements["CBAR"].pids.tolist() == tapered.elements["CBAR"].pids.tolist()
    twice = apply_effect(apply_effect(both, bow, [0.03, 0.0]), bow, [0.0, -0.02])
    once = apply_effect(tapered, bow, [0.08, -0.02])
    np.testing.assert_allclose(twice.grids.xyz, once.grids.xyz, atol=1e-15)
    for got, want in zip(assemble_g(twice), assemble_g(once)):
        assert abs(got - want).max() <= 1e-12 * abs(want).max()
    xs = np.linspace(0.0, 4.0, 9)[1:-1]
    np.testing.assert_allclose(once.grids.xyz[2:], np.column_stack(
        [xs, 4 * 0.08 * 4.0 * xs / 4.0 * (1 - xs / 4.0),
         -4 * 0.02 * 4.0 * xs / 4.0 * (1 - xs / 4.0)]),
        atol=1e-15)


@pytest.mark.parametrize("ends", ["GG", "BB"])
def test_bow_moves_the_grids_in_a_rotated_displacement_frame(tmp_path, ends):
    """Eight CBARs along x on grids whose CD frame is turned 30 deg about z, bowed by b in
    plane 1 (basic y): every grid moves to the parabola's (x, 4 b L xi (1 - xi), 0) at its xi =
    k / 8 (basic, whatever the CD frame), the end grids stay, and the end offsets and flags are
    left as they were ('G' or 'B'; the reader accepts only G / O end flags, so the 'B' one is set
    on the model). A CONM2 on the middle grid moves with it: the model's CG moves by b L m_c / m
    in y, by hand (the bars are massless)."""
    length, bow, turn, m_c = 4.0, 0.05, np.radians(30.0), 2.0
    cards = [("CORD2R", 5, None, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, np.cos(turn), np.sin(turn), 0.0)]
    cards += [("GRID", i + 1, None, length * i / 8, 0.0, 0.0, 5, 123456 if i == 0 else None)
              for i in range(9)]
    cards += [("CBAR", 100 + i, 7, i + 1, i + 2, 0.0, 1.0, 0.0, "BGG") for i in range(8)]
    cards += [("PBAR", 7, 1, 3.0, 0.7, 1.3, 1.0), ("MAT1", 1, 2.0e5, None, 0.3, 0.0),
              ("CONM2", 900, 5, None, m_c), ("CONM2", 901, 9, None, 3.0)]
    model = read_model(small_deck(tmp_path, "turned.bdf", cards))
    es = model.elements["CBAR"]
    data = {**es.data, "offt": np.array(["B" + ends] * 8)}
    model = replace(model, elements={"CBAR": replace(es, data=data)})
    cand = pick(candidates(model, ["member_curvature"]), "member_curvature", "+y +z")
    bent = apply_effect(model, cand, [bow, 0.0])
    bowed = bent.elements["CBAR"]
    assert bowed.data["offt"].tolist() == ["B" + ends] * 8
    for key in ("wa", "wb"):
        np.testing.assert_array_equal(bowed.data[key], es.data[key])
    xi = np.arange(9) / 8
    expected = np.column_stack([length * xi, 4.0 * bow * length * xi * (1.0 - xi),
                                np.zeros(9)])
    np.testing.assert_allclose(bent.grids.xyz[bent.grids.index(np.arange(1, 10))], expected,
                               atol=1e-15)
    shift = mass_properties(bent).cg - mass_properties(model).cg
    np.testing.assert_allclose(shift, [0.0, bow * length * m_c / (m_c + 3.0), 0.0], atol=1e-14)


# ------------------------------------------------------------------------------- rigid joints
@pytest.mark.parametrize("label, compliance", [("RBE2 7501", 1e-6), ("RBE2 7601", 1e-6),
                                               ("RBE2 7005", 1e-5)])
def test_joint_compliance_tends_to_the_rigid_joint(x56, x56_candidates, label, compliance):
    """The engine mounts at compliance 1e-6; the wing-rib joint 7005 at 1e-5, because at 1e-6
    its spring (1e6 x the spar's E I / L) leaves round-off of 2e-6 x the first elastic eigenvalue
    in the rigid-body ones, which structures.modal rejects (limit 1e-6)."""
    cand = pick(x56_candidates, "joint_flexibility", label)
    rigid = elastic(x56, 20)
    stiff = elastic(apply_effect(x56, cand, [compliance, 0.0]), 20)
    np.testing.assert_allclose(stiff, rigid, rtol=1e-4)
    soft = elastic(apply_effect(x56, cand, [cand.upper[0], 0.0]), 20)
    assert np.all(soft <= rigid * (1 + 1e-9))      # a released constraint never stiffens
    if label != "RBE2 7005":
        assert np.max(1 - soft / rigid) > 0.05      # the engine mount is clearly visible


@pytest.mark.parametrize("rho", [0.0, 0.8, -1.5])
def test_one_dependent_grid_on_its_spring(tmp_path, rho):
    """A clamped grid 1 carries grids 2 and 3 (coincident with 1, so its CBUSH has no length to
    couple translation and rotation) on an RBE2 (masses m2, m3 with inertia i3; a bar 1-4 gives
    k_ref). The one-dependent candidate of grid 3 at compliance c and rotation rho leaves 2 rigid
    and hangs 3 on a CBUSH of k_t / c_t, k_r / c_r (k_r = k_t i3 / m3, c_t = c 10^(-rho / 2),
    c_r = c 10^(rho / 2)): by hand, the only modes are sqrt(k_t / (c_t m3)) (x3) and
    sqrt(k_r / (c_r i3)) (x3); the written deck reads back to the same K and M."""
    m2, m3, i3, c = 5.0, 2.0, 0.01, 300.0
    c_t, c_r = c * 10.0 ** (-rho / 2), c * 10.0 ** (rho / 2)
    deck = hinge_deck(tmp_path, m2, m3, i3)
    model = read_model(deck)
    joints = candidates(model, ["joint_flexibility"])
    assert sorted(j.label for j in joints) == ["RBE2 10 (1-2 only)", "RBE2 10 (1-2/3)",
                                               "RBE2 10 (1-3 only)"]
    cand = pick(joints, "joint_flexibility", "(1-3 only)")
    kt, kr = cand.get("k_translation"), cand.get("k_rotation")
    ei = 7.0e10 * 0.5 * (2e-7 + 4e-7)
    assert (kt, kr) == pytest.approx((12 * ei, 12 * ei * i3 / m3), rel=1e-12)   # L = 1
    changed = apply_effect(model, cand, [c, rho])
    assert [r.dependent for r in changed.rigid] == [((2, "123456"),)]
    f = np.sort(compute_modes(changed, 6)["frequency"].values)
    expected = np.sort([np.sqrt(kt / (c_t * m3)) / (2 * np.pi)] * 3 +
                       [np.sqrt(kr / (c_r * i3)) / (2 * np.pi)] * 3)
    np.testing.assert_allclose(f, expected, rtol=1e-8)
    back = read_model(write_effect_deck(deck, tmp_path / "hinge_out.bdf", model,
                                        [(cand, [c, rho])]))
    for got, want in zip(assemble_g(back), assemble_g(changed)):
        assert abs(got - want).max() <= 1e-12 * abs(want).max()
    assert [r.dependent for r in back.rigid] == [((2, "123456"),)]


def test_whole_rbe2_hangs_on_one_spring(tmp_path):
    """Grids 2 (mass m2 at x = a, inertia i) and 3 (m3 at x = -b, b = a m2 / m3: CG on grid 1)
    on an RBE2 at the clamped grid 1 (a bar 1-4 gives k_ref). The whole-joint candidate keeps
    the RBE2 rigid on a new grid hung by one CBUSH at grid 1: by hand, translations
    sqrt(k_t / (c M)) (x3), roll sqrt(k_r / (c i)), pitch and yaw sqrt(k_r / (c (m2 a^2 + m3 b^2
    + i))), with k_r = k_t (m2 a^2 + m3 b^2 + i) / (m2 + m3) (documented scale); the deck
    reads back."""
    m2, m3, a, i, c = 5.0, 2.0, 0.3, 0.01, 300.0
    b = a * m2 / m3
    deck = small_deck(tmp_path, "store.bdf", [
        ("GRID", 1, None, 0.0, 0.0, 0.0, None, 123456), ("GRID", 2, None, a, 0.0, 0.0),
        ("GRID", 3, None, -b, 0.0, 0.0), ("GRID", 4, None, 0.0, 1.0, 0.0, None, 123456),
        ("RBE2", 10, 1, 123456, 2, 3), ("CONM2", 22, 3, None, m3),
        ("CONM2", 21, 2, None, m2, 0.0, 0.0, 0.0, None, i, 0.0, i, 0.0, 0.0, i),
        ("CBAR", 31, 41, 1, 4, 0.0, 0.0, 1.0), ("PBAR", 41, 51, 1e-3, 2e-7, 4e-7, 3e-7),
        ("MAT1", 51, 7.0e10, None, 0.33)])
    model = read_model(deck)
    cand = pick(candidates(model, ["joint_flexibility"]), "joint_flexibility", "(1-2/3)")
    kt, kr = cand.get("k_translation"), cand.get("k_rotation")
    ei = 7.0e10 * 0.5 * (2e-7 + 4e-7)
    pitch = m2 * a ** 2 + m3 * b ** 2 + i
    assert (kt, kr) == pytest.approx((12 * ei, 12 * ei * pitch / (m2 + m3)), rel=1e-12)
    changed = apply_effect(model, cand, [c, 0.0])
    assert changed.grids.ids.tolist() == [1, 2, 3, 4, 5]
    assert changed.rigid[0].independent == ((5, "123456"),)
    f = np.sort(compute_modes(changed, 6)["frequency"].values)
    expected = np.sort(np.sqrt(np.array([kt / m2 / (1 + m3 / m2)] * 3 + [kr / i]
                                        + [kr / pitch] * 2) / c) / (2 * np.pi))
    np.testing.assert_allclose(f, expected, rtol=1e-8)
    back = read_model(write_effect_deck(deck, tmp_path / "store_out.bdf", model,
                                        [(cand, [c, 0.0])]))
    for got, want in zip(assemble_g(back), assemble_g(changed)):
        assert abs(got - want).max() <= 1e-12 * abs(want).max()


def _condensed(system, n_grids):
    """K statically condensed onto the DOFs of the first ``n_grids`` grids, and M there (the
    rest must be massless)."""
    keep = system.a_dofs < 6 * n_grids
    k, m = system.K.tocsc(), system.M.tocsc()
    assert m[:, ~keep].count_nonzero() == 0
    k_on = k[keep][:, ~keep]
    cond = k[keep][:, keep] - k_on @ spla.spsolve(k[~keep][:, ~keep].tocsc(), k_on.T.tocsc())
    return system.a_dofs[keep], cond, m[keep][:, keep]


def test_zero_values_leave_k_and_m_and_small_values_are_continuous(x56, x56_candidates):
    """Members are split at new (massless) grids: their K condensed onto the model's grids."""
    base = assemble(x56, warn=False)
    picks = {"lumped_mass": "grid 3005", "joint_flexibility": "RBE2 7501",
             "member_taper": "PID 101 (CBAR 1003", "member_curvature": "PID 101 (CBAR 1003",
             "boundary_stiffness": "grid 3005 z"}
    for kind in KINDS:
        cand = pick(x56_candidates, kind, picks[kind])
        same = assemble(apply_effect(x56, cand, np.zeros(len(cand.parameters))), warn=False)
        assert (same.K != base.K).nnz == 0 and (same.M != base.M).nnz == 0
        if kind == "joint_flexibility":
            continue
        near = assemble(apply_effect(x56, cand, 1e-9 * np.array(cand.upper)), warn=False)
        dofs, k, m = _condensed(near, len(x56.grids))
        assert np.array_equal(dofs, base.a_dofs)
        for a, b in ((k, base.K), (m, base.M)):
            assert abs(a - b).max() <= 1e-7 * abs(b).max()


def test_effect_matrices_equal_the_difference_of_assembled_models(x56, x56_candidates):
    """Kinds that keep the grids; a member split by a first taper, then bowed (its new grids
    move) and tapered again (its pieces own their PIDs: changed in place)."""
    picks = {"lumped_mass": "grid 3005", "boundary_stiffness": "grid 3005 z"}
    k0, m0 = assemble_g(x56)
    for kind, label in picks.items():
        cand = pick(x56_candidates, kind, label)
        dk, dm = effect_matrices(x56, cand, cand.reference)
        k1, m1 = assemble_g(apply_effect(x56, cand, cand.reference))
        for got, want, base in ((dk, k1 - k0, k0), (dm, m1 - m0, m0)):
            assert abs(got - want).max() <= 1e-13 * abs(base).max()
        assert abs(dk).max() + abs(dm).max() > 0
    taper = pick(x56_candidates, "member_taper", "PID 132")
    with pytest.raises(InputError, match="grids"):
        effect_matrices(x56, taper, taper.reference)
    split = apply_effect(x56, taper, taper.reference)
    k0, m0 = assemble_g(split)
    for kind in ("member_curvature", "member_taper"):
        cand = pick(x56_candidates, kind, "PID 132")
        dk, dm = effect_matrices(split, cand, cand.reference)
        k1, m1 = assemble_g(apply_effect(split, cand, cand.reference))
        assert abs(dk - (k1 - k0)).max() <= 1e-13 * abs(k0).max() and abs(dk).max() > 0
    with pytest.raises(InputError, match="rigid"):
        effect_matrices(x56, pick(x56_candidates, "joint_flexibility", "RBE2 7501"), [1.0])
