"""A grounded spring on its Ritz basis (pipeline.diagnose.grounded) against exact reanalysis of
the free-free frame, and the screening of a spring whose chi^2 valley the secant misses."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import lsq_linear

from pipeline.diagnose import screen
from pipeline.diagnose.apply import apply_effect
from pipeline.diagnose.calibrate import Problem
from pipeline.diagnose.effects import candidates
from pipeline.diagnose.evidence import evaluate
from pipeline.diagnose.fit_statistics import chi_square
from pipeline.diagnose.grounded import (FINEST_STEP, SPRING_LADDER, ladder_sizes, reduce_mass,
                                        reduce_spring, spring_basis)
from structures.bdf import read_model
from structures.massprops import mass_properties
from structures.modal import compute_modes
from tests.pipeline.diagnose.perfect_frame import perfect_reference
from tests.pipeline.diagnose.truth import frame


def _at(cand, size):
    """A candidate's parameters with the first at ``size`` and the others at 0 (a mass's
    inertia: a point mass)."""
    return np.r_[size, np.zeros(len(cand.parameters) - 1)]


@pytest.fixture(scope="module")
def frame_model(tmp_path_factory):
    model = read_model(frame.write_frame(tmp_path_factory.mktemp("frame")))
    return model, perfect_reference(model, model)[1]


def test_reduced_spring_modes_match_exact_reanalysis(frame_model):
    """Springs in x, y and z at three grids of the free-free frame, sizes 1e-3 to 1 of the bound
    (the spring's mode from below the first elastic one to above the measured ones): the modes on
    the Ritz basis (46 modes + the residual attachment vector) against compute_modes of the
    changed model (assembly with the CELAS2, dense eigen-solution of the whole a-set).
    Tolerances: elastic frequencies of the 26 modes the residual can pair 1e-5 relative
    (measured 1.9e-6), MAC at the 120 sensors 1 - 1e-5 (measured 1 - 1.5e-6); the rigid-body
    motions named as the exact reanalysis names them (5 left: the spring holds one)."""
    model, ref = frame_model
    basis = spring_basis(model, ref.sensor_index, ref.nmodes)
    labels = ("grid 4004 z", "grid 1005 y", "grid 6101 x")
    picked = [c for c in candidates(model, ("boundary_stiffness",)) if c.label in labels]
    assert len(picked) == 3
    for cand in picked:
        reduced = reduce_spring(basis, cand, 1e-3)
        for size in (1e-3, 1e-2, 0.1, 1.0):
            exact = compute_modes(apply_effect(model, cand, _at(cand, size)), ref.nmodes)
            modes, shapes = reduced.modes(size)
            names = exact["rigid_motion"].values
            assert list(modes["rigid_motion"].values) == list(names), (cand.label, size)
            nr = int(np.sum(names != ""))
            assert nr == 5
            f_e, f_r = exact["frequency"].values[nr:26], modes["frequency"].values[nr:26]
            assert f_r == pytest.approx(f_e, rel=1e-5), (cand.label, size)
            s_e = exact["shape"].values[nr:26][:, ref.sensor_index]
            s_r = shapes[nr:26]
            mac = np.einsum("ij,ij->i", s_e, s_r) ** 2 / (
                np.einsum("ij,ij->i", s_e, s_e) * np.einsum("ij,ij->i", s_r, s_r))
            assert mac.min() > 1.0 - 1e-5, (cand.label, size)


@pytest.mark.parametrize("label", ["grid 4004", "grid 3009", "grid 6101",
                                   "grid 2004 and its mirror image grid 3004"])
def test_reduced_mass_modes_match_exact_reanalysis(frame_model, label):
    """A point mass of 0.1 % to 10 % of the frame's mass (the library's bound) at a tail, wing,
    gear and a mirror pair of grids: the modes on the Ritz basis (46 modes + the three residual
    attachment vectors of the grid's translations, six for a pair; M(x) = M + mu E E^T) against
    compute_modes of the model with the CONM2, and the mass properties against
    structures.massprops of that model. The mass moves some of the 20 lowest elastic modes by
    up to 28 % (grid 4004 at 10 %), so this is no small change.
    Tolerances: frequencies 2e-5 relative (measured 3.8e-6), MAC at the 120 sensors 1 - 1e-6
    (measured 1 - 1.5e-7), the shapes' amplitude (mass normalisation in M(x)) 1e-3 (measured
    2.5e-4), mass properties 1e-6 (measured 1e-7); the six rigid-body motions kept."""
    model, ref = frame_model
    basis = spring_basis(model, ref.sensor_index, ref.nmodes)
    cand = next(c for c in candidates(model, ("lumped_mass",)) if c.label == label)
    reduced = reduce_mass(basis, cand)
    moved = 0.0
    for size in (1e-3, 1e-2, 0.05, 0.1):
        changed = apply_effect(model, cand, _at(cand, size))
        exact = compute_modes(changed, ref.nmodes)
        modes, shapes = reduced.modes(size)
        assert list(modes["rigid_motion"].values[:6]) == list(exact["rigid_motion"].values[:6])
        assert np.all(exact["rigid_motion"].values[:6] != "")
        f_e, f_r = exact["frequency"].values[6:26], modes["frequency"].values[6:26]
        assert f_r == pytest.approx(f_e, rel=2e-5), size
        s_e, s_r = exact["shape"].values[6:26][:, ref.sensor_index], shapes[6:26]
        dot = np.einsum("ij,ij->i", s_e, s_r)
        mac = dot ** 2 / (np.einsum("ij,ij->i", s_e, s_e) * np.einsum("ij,ij->i", s_r, s_r))
        assert mac.min() > 1.0 - 1e-6, size
        assert np.abs(dot) / np.einsum("ij,ij->i", s_e, s_e) == pytest.approx(1.0, abs=1e-3)
        want, got = mass_properties(changed).as_dict(), reduced.properties(size).as_dict()
        for q in ("mass", "x_cg", "z_cg", "Ixx", "Iyy", "Izz"):
            assert got[q] == pytest.approx(want[q], rel=1e-6), (size, q)
        moved = max(moved, float(np.max(np.abs(f_e / (basis.lam[6:26] ** 0.5 / 2 / np.pi) - 1))))
    assert moved > 0.05


@pytest.mark.parametrize("label, n_rigid", [("grid 2004 z and its mirror image grid 3004 z", 4),
                                            ("grid 2006 y and its mirror image grid 3006 y", 5)])
def test_reduced_mirror_pair_of_springs_matches_exact_reanalysis(frame_model, label, n_rigid):
    """A mirror pair: a spring of the same size at a grid and at its image (rank-two change, both
    residual attachment vectors in the basis) against compute_modes of the model with both
    CELAS2s; same tolerances as one spring. Two z springs hold plunge and roll (4 rigid motions
    left); two y springs at mirror points move alike in every rigid motion, so they hold one
    combination only (5 left); the motions named as the exact reanalysis names them."""
    model, ref = frame_model
    basis = spring_basis(model, ref.sensor_index, ref.nmodes)
    cand = next(c for c in candidates(model, ("boundary_stiffness",)) if c.label == label)
    reduced = reduce_spring(basis, cand, 1e-3)
    for size in (1e-3, 0.1, 1.0):
        exact = compute_modes(apply_effect(model, cand, _at(cand, size)), ref.nmodes)
        modes, shapes = reduced.modes(size)
        names = exact["rigid_motion"].values
        assert list(modes["rigid_motion"].values) == list(names), size
        nr = int(np.sum(names != ""))
        assert nr == n_rigid
        f_e, f_r = exact["frequency"].values[nr:26], modes["frequency"].values[nr:26]
        assert f_r == pytest.approx(f_e, rel=1e-5), size
        s_e = exact["shape"].values[nr:26][:, ref.sensor_index]
        s_r = shapes[nr:26]
        mac = np.einsum("ij,ij->i", s_e, s_r) ** 2 / (
            np.einsum("ij,ij->i", s_e, s_e) * np.einsum("ij,ij->i", s_r, s_r))
        assert mac.min() > 1.0 - 1e-5, size


def test_spring_ladder_finds_the_valley_the_secant_misses(frame_model):
    """A test made by the frame with a spring of size 0.3 at grid 4004 z (its mode sweeps
    through the measured ones: chi^2 over the size is far from linear). The secant through the
    exact reanalysis at the reference size 0.1 leaves chi^2 605 of 2696 at its best size
    (measured); the ladder on the Ritz basis finds the size within one rung
    (1/8 decade) of 0.3 with chi^2 below 5 (measured 0.13 at 0.305), and that chi^2 is the exact
    reanalysis's at the same size to 1e-3 + 0.01."""
    model, _ = frame_model
    cand = next(c for c in candidates(model, ("boundary_stiffness",)) if c.label == "grid 4004 z")
    problem, ref, theta, evs, r0, chi_lin = _made_by(model, cand, 0.3)
    assert chi_lin > 0.2 * chi_square(r0)                                 # the secant misses
    _, out, skipped = screen.signatures(problem, theta, (), evs, [cand])
    assert not skipped
    (x, chi2) = out[0][2]
    assert abs(np.log10(x[0] / 0.3)) <= 1.0 / 8.0
    assert chi2 < 5.0 < 0.01 * chi_lin
    assert chi2 == pytest.approx(_exact_chi2(problem, ref, model, cand, x), rel=1e-3, abs=0.01)


def _made_by(model, cand, size):
    """The frame against a perfect test of the frame with ``cand`` at ``size``: (problem, ref,
    theta 0, evaluations, r0, the chi^2 of the secant through the exact reanalysis at the
    candidate's reference size, fitted within its bounds)."""
    _, ref = perfect_reference(apply_effect(model, cand, _at(cand, size)), model)
    problem = Problem.build([ref], [model], 0.03)
    theta = np.zeros(len(problem.names))
    evs = problem.evaluate(theta)
    r0 = problem.residual(theta, evs)
    h = cand.reference[0]
    secant = ((_exact(problem, ref, model, cand, _at(cand, h)) - r0) / h)[:, None]
    fit = lsq_linear(secant, -r0, bounds=(cand.lower[:1], cand.upper[:1]))
    return problem, ref, theta, evs, r0, chi_square(r0 + secant @ fit.x)


def _exact(problem, ref, model, cand, x):
    theta = np.zeros(len(problem.names))
    return np.concatenate([evaluate(ref, apply_effect(model, cand, x)).vector(ref),
                           problem.prior_residual(theta)])


def _exact_chi2(problem, ref, model, cand, x):
    return chi_square(_exact(problem, ref, model, cand, x))


def test_mass_ladder_finds_the_size_and_the_grid(frame_model):
    """A test made by the frame with 6 % of its mass added at the tail grid 4004 (the mass's own
    mode falls through the measured ones). The secant at the reference size 0.02 (exact
    reanalysis) fits a size and chi^2 far off; the screening on the Ritz basis ranks grid 4004
    first among the mass candidates (126 point masses and pairs, and the spread ones), at a size
    within one rung (1/4 decade) of 0.06 and a chi^2 below 1 % of the nominal model's, which is
    the exact reanalysis's at that size to 1e-3 + 0.01. The mass spread over 4004 and its
    neighbours (equal shares on the Ritz basis's weighted load vectors) also matches its exact
    reanalysis at its screened size."""
    model, _ = frame_model
    masses = candidates(model, ("lumped_mass",))
    cand = next(c for c in masses if c.label == "grid 4004")
    problem, ref, theta, evs, r0, chi_lin = _made_by(model, cand, 0.06)
    _, out, skipped = screen.signatures(problem, theta, (), evs, masses)
    rows = screen.screen(r0, out)
    assert not skipped and len(rows) == len(masses)
    assert sum("spread" not in c.label for c in masses) == 126          # 88 grids, 38 pairs
    best = rows[0]
    assert best.candidate.label == "grid 4004"
    assert abs(np.log10(best.values[0] / 0.06)) <= 0.25
    assert best.chi2 < 0.01 * chi_square(r0) and best.chi2 < 0.1 * chi_lin
    assert best.chi2 == pytest.approx(_exact_chi2(problem, ref, model, cand, best.values),
                                      rel=1e-3, abs=0.01)
    spread = next(r for r in rows if r.candidate.label.startswith("grid 4004 spread over"))
    assert len(spread.candidate.location.grids) > 1 and spread.values[0] > 0
    assert spread.chi2 == pytest.approx(
        _exact_chi2(problem, ref, model, spread.candidate, spread.values), rel=1e-3, abs=0.01)


def test_ladder_sizes_refine_where_the_modes_turn(frame_model):
    """The rungs of grid 4004 z: every size of SPRING_LADDER is kept, the added ones lie
    between them, no interval is narrower than FINEST_STEP, and across every interval wider
    than FINEST_STEP no elastic mode turns by more than the limit (checked here directly with
    the overlaps of the reduced eigenvectors at its ends)."""
    model, ref = frame_model
    cand = next(c for c in candidates(model, ("boundary_stiffness",)) if c.label == "grid 4004 z")
    reduced = reduce_spring(spring_basis(model, ref.sensor_index, ref.nmodes), cand, 1e-3)
    sizes = ladder_sizes([reduced], 1.0)
    assert np.all(np.isin(np.round(np.asarray(SPRING_LADDER), 12), np.round(sizes, 12)))
    ratio = sizes[1:] / sizes[:-1]
    assert sizes.size > len(SPRING_LADDER) and np.all(ratio > FINEST_STEP ** 0.5)
    for a, b, q in zip(sizes[:-1], sizes[1:], ratio):
        if q > FINEST_STEP * 1.0001:
            (_, y_a), (lam_b, y_b) = reduced.solve(a), reduced.solve(b)
            kept = np.einsum("ij,ij->j", y_a, y_b) ** 2
            assert kept[lam_b > 0].min() >= 0.9 - 1e-12, (a, b)
