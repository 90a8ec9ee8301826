"""The candidate-effect library of diagnose: analytic spring-mass and beam references, hand
computations, the rigid-joint limit and the written deck read back."""
import re
import subprocess
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse.linalg as spla
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from pipeline.diagnose.effects import (KINDS, Candidate, Location, apply_effect, candidates,
                                       effect_cards, effect_matrices, neighbours,
                                       write_effect_deck)
from pipeline.diagnose.effect_deck import model_changes, write_patched_deck
from pipeline.diagnose.mirror import mirror_grids
from pipeline.diagnose.members import find_members
from structures.assembly import assemble, assemble_g
from structures.bdf import read_model
from structures.bulk_text import card
from structures.common.errors import InputError
from structures.massprops import mass_properties
from structures.modal import compute_modes
from structures.mystran import mystran_executable

X56 = Path(__file__).resolve().parents[3] / "data" / "x56_like" / "x56_efew.bdf"


def _deck(tmp_path, name, cards, params=()):
    text = "SOL 103\nCEND\nBEGIN BULK\n" + "".join(p + "\n" for p in params)
    text += "\n".join(card(*c) for c in cards) + "\nENDDATA\n"
    path = tmp_path / name
    path.write_text(text)
    return path


def _elastic(model, n):
    ds = compute_modes(model, n)
    f = ds["frequency"].values
    return f[ds["rigid_motion"].values == ""]


def _pick(cands, kind, label_part=""):
    return next(c for c in cands if c.kind == kind and label_part in c.label)


def _quadratic_frequencies(k, m):
    """Frequencies [Hz] of a 2-DOF system by the closed-form roots of det(K - lam M) = 0."""
    a = m[0] * m[1]
    b = -(k[0][0] * m[1] + k[1][1] * m[0])
    c = k[0][0] * k[1][1] - k[0][1] ** 2
    disc = np.sqrt(b * b - 4 * a * c)
    lam = np.array([(-b - disc) / (2 * a), (-b + disc) / (2 * a)])
    return np.sqrt(np.clip(lam, 0, None)) / (2 * np.pi)


# --------------------------------------------------------------------------- spring-mass decks
def test_lumped_mass_on_one_and_two_dof_spring_mass(tmp_path):
    k1, k2, m1, m2 = 4.0e3, 2.5e3, 2.0, 3.0
    one = read_model(_deck(tmp_path, "one.bdf", [
        ("GRID", 1, None, 0.0, 0.0, 0.0, None, 12456), ("CELAS2", 11, k1, 1, 3),
        ("CONM2", 21, 1, None, m1)]))
    cand = _pick(candidates(one, ["lumped_mass"]), "lumped_mass", "grid 1")
    f = _elastic(apply_effect(one, cand, [0.05, 0.0]), 1)
    assert f[0] == pytest.approx(np.sqrt(k1 / (1.05 * m1)) / (2 * np.pi), rel=1e-10)

    two = read_model(_deck(tmp_path, "two.bdf", [
        ("GRID", 1, None, 0.0, 0.0, 0.0, None, 12456),
        ("GRID", 2, None, 1.0, 0.0, 0.0, None, 12456),
        ("CELAS2", 11, k1, 1, 3), ("CELAS2", 12, k2, 1, 3, 2, 3),
        ("CONM2", 21, 1, None, m1), ("CONM2", 22, 2, None, m2)]))
    cand = _pick(candidates(two, ["lumped_mass"]), "lumped_mass", "grid 2")
    p = 0.08
    f = _elastic(apply_effect(two, cand, [p, 0.0]), 2)
    expected = _quadratic_frequencies([[k1 + k2, -k2], [-k2, k2]], [m1, m2 + p * (m1 + m2)])
    np.testing.assert_allclose(f, expected, rtol=1e-10)


def test_lumped_mass_inertia_on_a_torsion_spring(tmp_path):
    """Grid 1 moves along x on a spring k_x and turns about x on a torsion spring k (CELAS2 on
    components 1 and 4) and carries a CONM2 of mass m and I11 = i; a clamped grid 2 at distance
    2 makes the model's size L = 2. A mass p m with inertia q adds p m q L^2 about each axis: by
    hand the modes are sqrt(k_x / ((1 + p) m)) / 2 pi and sqrt(k / (i + p m q L^2)) / 2 pi."""
    k_x, k, m, i, p, q = 5.0e3, 3.0e3, 4.0, 0.5, 0.05, 4e-3
    model = read_model(_deck(tmp_path, "torsion.bdf", [
        ("GRID", 1, None, 0.0, 0.0, 0.0, None, 2356),
        ("GRID", 2, None, 2.0, 0.0, 0.0, None, 123456), ("CELAS2", 11, k, 1, 4),
        ("CELAS2", 12, k_x, 1, 1),
        ("CONM2", 21, 1, None, m, 0.0, 0.0, 0.0, None, i, 0.0, i, 0.0, 0.0, i)]))
    cand = _pick(candidates(model, ["lumped_mass"]), "lumped_mass", "grid 1")
    f = compute_modes(apply_effect(model, cand, [p, q]), 2)["frequency"].values
    expected = [np.sqrt(k_x / ((1 + p) * m)), np.sqrt(k / (i + p * m * q * 2.0 ** 2))]
    np.testing.assert_allclose(np.sort(f), np.sort(expected) / (2 * np.pi), rtol=1e-10)


def test_grounded_spring_on_free_free_two_masses(tmp_path):
    k, m1, m2 = 1.0e4, 2.0, 5.0
    model = read_model(_deck(tmp_path, "free.bdf", [
        ("GRID", 1, None, 0.0, 0.0, 0.0, None, 12456),
        ("GRID", 2, None, 1.0, 0.0, 0.0, None, 12456),
        ("CELAS2", 12, k, 1, 3, 2, 3), ("CONM2", 21, 1, None, m1), ("CONM2", 22, 2, None, m2)]))
    f_elastic = np.sqrt(k * (m1 + m2) / (m1 * m2)) / (2 * np.pi)
    assert _elastic(model, 2)[0] == pytest.approx(f_elastic, rel=1e-10)
    cands = candidates(model, ["boundary_stiffness"])
    assert sorted(c.label for c in cands) == ["grid 1 z", "grid 2 z"]   # x, y fixed by PS
    p = 0.3
    k_ground = p * (m1 + m2) * (2 * np.pi * f_elastic) ** 2    # the documented scale
    f = compute_modes(apply_effect(model, _pick(cands, "boundary_stiffness", "grid 1 z"), [p]),
                      2)["frequency"].values
    np.testing.assert_allclose(f, _quadratic_frequencies([[k + k_ground, -k], [-k, k]], [m1, m2]),
                               rtol=1e-9)


def test_total_mass_and_cg_follow_the_added_mass(x56, x56_candidates):
    before = mass_properties(x56)
    cand = _pick(x56_candidates, "lumped_mass", "grid 3005")
    p = 0.037
    after = mass_properties(apply_effect(x56, cand, [p, 0.0]))
    assert after.mass - before.mass == pytest.approx(p * before.mass, rel=1e-12)
    x_grid = x56.grids.xyz[x56.grids.index([3005])[0]]
    np.testing.assert_allclose(after.cg, (before.cg + p * x_grid) / (1 + p), rtol=1e-12)
    # spread in equal shares over the pylon base, its top and the engine: the CG moves towards
    # the three grids' centroid, and each carries a third of the mass
    spread = _pick(x56_candidates, "lumped_mass", "grid 5111 spread over 5101, 5121")
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
    cand = _pick(x56_candidates, "member_taper", "PID 101 (CBAR 1003")
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
    return read_model(_deck(tmp_path, f"cantilever{n}.bdf", cards, ["PARAM,COUPMASS,1"]))


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
    cand = _pick(candidates(model, ["member_taper"]), "member_taper")
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
    return read_model(_deck(tmp_path, "one_bar.bdf", [
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
    cand = _pick(candidates(model, ["member_curvature"]), "member_curvature")
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
    cand = _pick(candidates(model, ["member_taper"]), "member_taper")
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
        [xs, 4 * 0.08 * 4.0 * xs / 4.0 * (1 - xs / 4.0), -4 * 0.02 * 4.0 * xs / 4.0 * (1 - xs / 4.0)]),
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
    model = read_model(_deck(tmp_path, "turned.bdf", cards))
    es = model.elements["CBAR"]
    data = {**es.data, "offt": np.array(["B" + ends] * 8)}
    model = replace(model, elements={"CBAR": replace(es, data=data)})
    cand = _pick(candidates(model, ["member_curvature"]), "member_curvature", "+y +z")
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
    cand = _pick(x56_candidates, "joint_flexibility", label)
    rigid = _elastic(x56, 20)
    stiff = _elastic(apply_effect(x56, cand, [compliance, 0.0]), 20)
    np.testing.assert_allclose(stiff, rigid, rtol=1e-4)
    soft = _elastic(apply_effect(x56, cand, [cand.upper[0], 0.0]), 20)
    assert np.all(soft <= rigid * (1 + 1e-9))      # a released constraint never stiffens
    if label != "RBE2 7005":
        assert np.max(1 - soft / rigid) > 0.05      # the engine mount is clearly visible


def _hinge_deck(tmp_path, m2, m3, i3):
    """Clamped grid 1 carrying grids 2 (x = 0.3, mass m2) and 3 (coincident with 1, mass m3,
    inertia i3) on RBE2 10; a bar 1-4 (clamped at 4) gives k_ref."""
    return _deck(tmp_path, "hinge.bdf", [
        ("GRID", 1, None, 0.0, 0.0, 0.0, None, 123456), ("GRID", 2, None, 0.3, 0.0, 0.0),
        ("GRID", 3, None, 0.0, 0.0, 0.0), ("GRID", 4, None, 0.0, 1.0, 0.0, None, 123456),
        ("RBE2", 10, 1, 123456, 2, 3), ("CONM2", 21, 2, None, m2),
        ("CONM2", 22, 3, None, m3, 0.0, 0.0, 0.0, None, i3, 0.0, i3, 0.0, 0.0, i3),
        ("CBAR", 31, 41, 1, 4, 0.0, 0.0, 1.0), ("PBAR", 41, 51, 1e-3, 2e-7, 4e-7, 3e-7),
        ("MAT1", 51, 7.0e10, None, 0.33)])


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
    deck = _hinge_deck(tmp_path, m2, m3, i3)
    model = read_model(deck)
    joints = candidates(model, ["joint_flexibility"])
    assert sorted(j.label for j in joints) == ["RBE2 10 (1-2 only)", "RBE2 10 (1-2/3)",
                                               "RBE2 10 (1-3 only)"]
    cand = _pick(joints, "joint_flexibility", "(1-3 only)")
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
    deck = _deck(tmp_path, "store.bdf", [
        ("GRID", 1, None, 0.0, 0.0, 0.0, None, 123456), ("GRID", 2, None, a, 0.0, 0.0),
        ("GRID", 3, None, -b, 0.0, 0.0), ("GRID", 4, None, 0.0, 1.0, 0.0, None, 123456),
        ("RBE2", 10, 1, 123456, 2, 3), ("CONM2", 22, 3, None, m3),
        ("CONM2", 21, 2, None, m2, 0.0, 0.0, 0.0, None, i, 0.0, i, 0.0, 0.0, i),
        ("CBAR", 31, 41, 1, 4, 0.0, 0.0, 1.0), ("PBAR", 41, 51, 1e-3, 2e-7, 4e-7, 3e-7),
        ("MAT1", 51, 7.0e10, None, 0.33)])
    model = read_model(deck)
    cand = _pick(candidates(model, ["joint_flexibility"]), "joint_flexibility", "(1-2/3)")
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
        cand = _pick(x56_candidates, kind, picks[kind])
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
        cand = _pick(x56_candidates, kind, label)
        dk, dm = effect_matrices(x56, cand, cand.reference)
        k1, m1 = assemble_g(apply_effect(x56, cand, cand.reference))
        for got, want, base in ((dk, k1 - k0, k0), (dm, m1 - m0, m0)):
            assert abs(got - want).max() <= 1e-13 * abs(base).max()
        assert abs(dk).max() + abs(dm).max() > 0
    taper = _pick(x56_candidates, "member_taper", "PID 132")
    with pytest.raises(InputError, match="grids"):
        effect_matrices(x56, taper, taper.reference)
    split = apply_effect(x56, taper, taper.reference)
    k0, m0 = assemble_g(split)
    for kind in ("member_curvature", "member_taper"):
        cand = _pick(x56_candidates, kind, "PID 132")
        dk, dm = effect_matrices(split, cand, cand.reference)
        k1, m1 = assemble_g(apply_effect(split, cand, cand.reference))
        assert abs(dk - (k1 - k0)).max() <= 1e-13 * abs(k0).max() and abs(dk).max() > 0
    with pytest.raises(InputError, match="rigid"):
        effect_matrices(x56, _pick(x56_candidates, "joint_flexibility", "RBE2 7501"), [1.0])


# ----------------------------------------------------------------------------- written decks
def test_written_deck_reads_back_to_the_same_model(x56, x56_candidates, tmp_path):
    """Every kind alone and all together: the same assembled K and M, and the same modes."""
    picks = [("lumped_mass", "grid 5021"), ("lumped_mass", "grid 3005 spread over"),
             ("joint_flexibility", "RBE2 7501"),
             ("member_taper", "PID 101 (CBAR 1003"), ("member_curvature", "PID 101 (CBAR 1003"),
             ("member_curvature", "PID 132"), ("boundary_stiffness", "grid 1004 z")]
    effects = []
    for kind, label in picks:
        cand = _pick(x56_candidates, kind, label)
        values = np.array(cand.reference) * 1.7
        effects.append((cand, values))
        expected = assemble_g(apply_effect(x56, cand, values))
        path = write_effect_deck(X56, tmp_path / f"{kind}.bdf", x56, [(cand, values)])
        for got, want in zip(assemble_g(read_model(path)), expected):
            assert abs(got - want).max() <= 1e-10 * abs(want).max()
    combined = x56
    for cand, values in effects:
        combined = apply_effect(combined, cand, values)
    back = read_model(write_effect_deck(X56, tmp_path / "all.bdf", x56, effects))
    for got, want in zip(assemble_g(back), assemble_g(combined)):
        assert abs(got - want).max() <= 1e-12 * abs(want).max()
    # K and M agree to 3e-15; the eigen-solver reproduces the grounded spring's 1.42 Hz bounce
    # mode of these equal matrices to 3e-8 only, hence 1e-7 on the modes.
    np.testing.assert_allclose(_elastic(back, 20), _elastic(combined, 20), rtol=1e-7)


def test_cbeam_members_round_trip(tmp_path):
    """CBEAM/PBEAM (shear factors K1, K2) through taper and curvature, both written forms."""
    cards = [("GRID", i + 1, None, 2.0 * i, 0.3 * i, 0.0, None, 123456 if i == 0 else None)
             for i in range(5)]
    cards += [("CBEAM", 20 + i, 8, i + 1, i + 2, 0.0, 0.0, 1.0) for i in range(4)]
    cards += [("PBEAM", 8, 1, 2.0, 0.4, 0.9, 0.05, 0.6, 0.1, *[0.0] * 8, 0.85, 0.8),
              ("MAT1", 1, 7.0e4, None, 0.33, 2.7e-3)]
    deck = _deck(tmp_path, "beams.bdf", cards)
    model = read_model(deck)
    cands = candidates(model, ["member_taper", "member_curvature"])
    assert [c.location.elements for c in cands] == [(20, 21, 22, 23)] * 5
    effects = [(cands[0], [-0.1, 0.4]), (cands[2], [0.08, -0.05])]
    combined = apply_effect(apply_effect(model, *effects[0]), *effects[1])
    back = read_model(write_effect_deck(deck, tmp_path / "beams_out.bdf", model, effects))
    for got, want in zip(assemble_g(back), assemble_g(combined)):
        assert abs(got - want).max() <= 1e-12 * abs(want).max()
    text = effect_cards(model, *effects[0])
    assert "replaces or removes element 20 21 22 23" in text
    path = _deck(tmp_path, "beams_small.bdf", [c for c in cards if c[0] != "CBEAM"])
    path.write_text(path.read_text().replace("ENDDATA", text + "ENDDATA"))
    np.testing.assert_allclose(compute_modes(read_model(path), 6)["frequency"].values,
                               compute_modes(apply_effect(model, *effects[0]), 6)
                               ["frequency"].values, rtol=1e-5)


def test_a_moved_grid_keeps_its_cd_and_ps(tmp_path):
    """Grid 2 given in CP 5 with CD 5 (a frame turned 30 deg about z, origin (1, 2, 0)) and PS 4,
    moved by (0.1, -0.2, 0.3): its card is written at the basic position with CD 5 and PS 4, and
    the patched deck reads back to the moved model's grids and K, M (CD sets the g-set axes)."""
    turn = np.radians(30.0)
    deck = _deck(tmp_path, "turned.bdf", [
        ("CORD2R", 5, None, 1.0, 2.0, 0.0, 1.0, 2.0, 1.0, 1.0 + np.cos(turn), 2.0 + np.sin(turn),
         0.0),
        ("GRID", 1, None, 0.0, 0.0, 0.0, None, 123456), ("GRID", 2, 5, 2.0, 0.0, 0.0, 5, 4),
        ("CBAR", 10, 7, 1, 2, 0.0, 0.0, 1.0), ("PBAR", 7, 1, 3.0, 0.7, 1.3, 1.0),
        ("MAT1", 1, 2.0e5, None, 0.3, 7.8e-9)])
    model = read_model(deck)
    assert model.grids.cd.tolist() == [0, 5] and model.grids.ps.tolist() == [63, 8]
    xyz = model.grids.xyz.copy()
    xyz[1] += [0.1, -0.2, 0.3]
    moved = replace(model, grids=replace(model.grids, xyz=xyz))
    removed, cards = model_changes(model, moved)
    assert removed["grids"] == [2]
    assert cards == [["GRID", 2, None, *xyz[1].tolist(), 5, 4]]
    back = read_model(write_patched_deck(deck, tmp_path / "turned_out.bdf", [(removed, cards)]))
    np.testing.assert_allclose(back.grids.xyz, xyz, atol=1e-14)
    assert back.grids.cd.tolist() == [0, 5] and back.grids.ps.tolist() == [63, 8]
    np.testing.assert_allclose(back.grids.cd_axes, model.grids.cd_axes, atol=1e-15)
    for got, want in zip(assemble_g(back), assemble_g(moved)):
        assert abs(got - want).max() <= 1e-12 * abs(want).max()


def test_effect_cards_are_readable_small_field_bulk_data(x56, x56_candidates, tmp_path):
    """Additive effects: the original deck plus the small-field cards gives the effect's modes
    (to the 8-character precision of the fields)."""
    for kind, label in (("lumped_mass", "grid 5021"), ("boundary_stiffness", "grid 1004 z")):
        cand = _pick(x56_candidates, kind, label)
        text = effect_cards(x56, cand, cand.reference)
        assert text.startswith("$ diagnose effect")
        assert all(len(line) <= 72 for line in text.splitlines() if not line.startswith("$"))
        deck = X56.read_text().replace("ENDDATA", text + "ENDDATA")
        (tmp_path / "structure_x56.inc").write_text((X56.parent / "structure_x56.inc").read_text())
        for inc in ("masses_efew.inc", "aero_x56.inc"):
            (tmp_path / inc).write_text((X56.parent / inc).read_text())
        path = tmp_path / f"{kind}_cards.bdf"
        path.write_text(deck)
        np.testing.assert_allclose(_elastic(read_model(path), 20),
                                   _elastic(apply_effect(x56, cand, cand.reference), 20),
                                   rtol=1e-5)


def _deck_with_cards(folder, texts, nmodes):
    """The X-56 structure and EFEW masses as one SOL 103 deck with effect cards: cards the
    effects' ``$ replaces or removes`` comments name are dropped first."""
    drop = {"rigid element": "RBE2", "element": "CBAR", "property": "PBAR"}
    removed = set()
    for text in texts:
        for line in text.splitlines():
            hit = re.match(r"\$ replaces or removes (rigid element|element|property) (.*)", line)
            if hit:
                removed |= {(drop[hit.group(1)], int(i)) for i in hit.group(2).split()}
    lines = ((X56.parent / "structure_x56.inc").read_text().splitlines()
             + (X56.parent / "masses_efew.inc").read_text().splitlines())
    bulk, keep = [], True
    for line in lines:
        if line[:1] not in (" ", "+", "*"):
            keep = (line[:8].strip(), int(line[8:16]) if line[8:16].strip().isdigit() else None) \
                not in removed
        if keep:
            bulk.append(line)
    path = folder / "effects.bdf"
    path.write_text("SOL 103\nCEND\nMETHOD = 1\nDISP(PLOT) = ALL\nBEGIN BULK\n" + "\n".join(bulk)
                    + "\n" + "".join(texts) + card("EIGRL", 1, None, None, nmodes) + "\nENDDATA\n")
    return path


@pytest.mark.skipif(mystran_executable() is None, reason="mystran is not installed")
def test_effect_cards_against_mystran(x56, x56_candidates, tmp_path):
    """MYSTRAN on the deck with the small-field cards of four effects (CONM2, CBUSH/PBUSH for
    a removed RBE2, re-PIDed tapered CBARs, bowed CBAR offsets) against apply_effect. (MYSTRAN
    18 rejects grounded springs, so boundary_stiffness is left out.)"""
    from pyNastran.op2.op2 import read_op2

    picks = [("lumped_mass", "grid 5021", [0.03, 2e-4]), ("joint_flexibility", "RBE2 7501", [4.0, 0.6]),
             ("member_taper", "PID 101 (CBAR 1003", [0.1, 0.5]),
             ("member_curvature", "PID 132 (CBAR 5002, grids 5001-5011) bow +y -z", [0.05, -0.05])]
    model, texts = x56, []
    for kind, label, values in picks:
        cand = _pick(x56_candidates, kind, label)
        texts.append(effect_cards(model, cand, values))
        model = apply_effect(model, cand, values)
    deck = _deck_with_cards(tmp_path, texts, 20)
    subprocess.run([mystran_executable(), deck.name], cwd=tmp_path, capture_output=True,
                   timeout=300)
    errors = [line for line in deck.with_suffix(".F06").read_text(errors="replace").splitlines()
              if "*ERROR" in line or "FATAL" in line]
    assert not errors
    table = next(iter(read_op2(str(deck.with_suffix(".OP2")), debug=None).eigenvectors.values()))
    theirs = np.sqrt(np.clip(np.asarray(table.eigns, float), 0, None)) / (2 * np.pi)
    ours = compute_modes(model, 20)["frequency"].values
    np.testing.assert_allclose(theirs[6:], ours[6:len(theirs)], rtol=1e-6)
    assert np.max(np.abs(ours[6:] / _elastic(x56, 20)[:14] - 1)) > 0.01   # the effects show


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
    assert _pick(x56_candidates, "lumped_mass", "grid 5111 spread over 5101, 5121"
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
    cand = _pick(x56_candidates, "lumped_mass", "grid 3005")
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
    model = read_model(_hinge_deck(tmp_path, 5.0, m3, i3))
    cand = _pick(candidates(model, ["joint_flexibility"]), "joint_flexibility", "(1-3 only)")
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
