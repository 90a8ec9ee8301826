"""Nominal calibration of diagnose (pipeline.diagnose.calibrate): the mass scale's prior, the
weighing it keeps, model-form flags."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from pipeline.diagnose.calibrate import Problem, calibrate, mass_prior_scale
from pipeline.diagnose.evidence import build_reference, holdout_mask
from pipeline.diagnose.fit_statistics import runs_test
from structures.bdf import read_model
from structures.gvt import make_gvt_dataset
from structures.massprops import mass_properties
from structures.modal import compute_modes
from tests.pipeline.chain_deck import chain_deck


def test_calibration_jacobian_holds_the_pairing():
    """A residual whose pairing flips under any step (a test mode tied between two analysis
    modes: here the pairing is the parity of theta / 1e-7 and the paired mode's entry is 5
    larger) is continuous for a held pairing, r = (theta - 0.03 + 5 p) / 0.01. The calibration's
    Jacobian (reused by every refit) is its derivative 1 / 0.01 = 100, not the jump over the
    step (5 / 0.01 / 2e-6 = 2.5e8, what differences that re-pair give)."""
    ref = SimpleNamespace(train=np.array([True]), name="c")

    def evaluate(theta, effects=(), paired=None):
        p = int(np.floor(theta[0] / 1e-7)) % 2 if paired is None else paired[0]
        r = np.array([(theta[0] - 0.03 + 5.0 * p) / 0.01])
        return [SimpleNamespace(frequency=r, paired=p, vector=lambda ref, r=r: r)]

    problem = SimpleNamespace(n_theta=1, names=("E1",), refs=(ref,), evaluate=evaluate,
                              prior=np.array([np.inf]), bounds=np.array([0.1]),
                              residual=lambda theta, evs: evs[0].vector(ref))
    cal = calibrate(problem)
    assert cal.jacobian[:, 0] == pytest.approx([100.0], rel=1e-9)


def test_calibration_runs_test_sees_the_training_modes_only():
    """30 modes, every third held out. Training residuals +1 (first ten) then -1 (last ten): two
    runs in 20, p = 1.8e-5, flagged. The held-out modes carry the opposite sign of their
    neighbours: with them the sequence has 20 runs (p > 0.01), so a flag proves that the
    held-out modes were left out."""
    held = holdout_mask(30, 3)
    train = ~held
    v = np.where(np.arange(30) < 15, 1.0, -1.0)
    v[held] *= -1.0
    assert runs_test(v) > 0.01 and runs_test(v[train]) < 1e-4

    def evaluate(theta, effects=(), paired=None):
        r = v + theta[0]
        return [SimpleNamespace(frequency=r, paired=np.arange(30),
                                vector=lambda ref, r=r: r[ref.train])]

    ref = SimpleNamespace(train=train, name="c")
    problem = SimpleNamespace(n_theta=1, names=("E1",), refs=(ref,), evaluate=evaluate,
                              prior=np.array([np.inf]), bounds=np.array([0.1]),
                              residual=lambda theta, evs: evs[0].vector(ref))
    cal = calibrate(problem)
    assert abs(cal.theta[0]) < 1e-6                       # ten +1, ten -1: no shift
    assert any("runs test" in flag for flag in cal.flags)


def _chain_problem(tmp_path, weight_factor: float, scatter: float = 0.03):
    """The chain deck against its own six lowest elastic frequencies (frequency-only) and a
    weighing ``weight_factor`` times its weight: a mass the model lacks that moves no frequency
    pattern, only the weighing."""
    deck = tmp_path / "chain.bdf"
    chain_deck(deck)
    model = read_model(deck)
    modes = compute_modes(model, 18)
    elastic = np.flatnonzero(modes["frequency"].values > 1e-3)[:6]
    gvt = make_gvt_dataset(modes["frequency"].values[elastic], np.eye(6), np.arange(6) + 1,
                           np.ones(6, int)).drop_vars("shape")
    weight = mass_properties(model).weight
    ref, _ = build_reference("chain", model, gvt, {"weight": weight_factor * weight}, modes,
                             frequency_noise=0.01, shape_noise_value=None, model_scatter=scatter,
                             holdout=3, nmodes=18)
    return Problem.build((ref,), (model,), scatter), ref, weight


def test_mass_prior_scale_by_hand(tmp_path):
    """sigma_m = s sqrt(sum m^2) / sum m: chain masses 1.0, 1.2, 1.4 twice give
    0.03 sqrt(8.8) / 7.2 = 0.0123603; N equal masses give s / sqrt(N)."""
    problem, _, _ = _chain_problem(tmp_path, 1.0)
    assert problem.names == ("mass",)                       # springs only: no material
    assert problem.prior[0] == pytest.approx(0.03 * np.sqrt(8.8) / 7.2, rel=1e-12)
    assert problem.prior[0] == pytest.approx(0.0123603, rel=1e-5)
    equal = SimpleNamespace(masses=SimpleNamespace(mass=np.full(25, 3.0)))
    assert mass_prior_scale(equal, 0.03) == pytest.approx(0.03 / 5.0, rel=1e-12)
    theta = np.array([0.02])
    r = problem.residual(theta, problem.evaluate(theta))
    assert r[-1] == pytest.approx(0.02 / problem.prior[0], rel=1e-12)   # the prior row, last
    exact, _, _ = _chain_problem(tmp_path, 1.0, scatter=0.0)
    assert exact.names == () and exact.prior.size == 0      # exact masses: no mass parameter


def test_calibration_keeps_the_weighing(tmp_path):
    """The test is the model's own frequencies, the weighing 6 % heavier. A uniform mass scale
    theta moves every frequency by (1 + theta)^-1/2 and the weight by (1 + theta), so the
    calibration minimises, by hand,
        r^T C^-1 r + ((1 + theta) W0 - W) / (0.005 W))^2 + (theta / sigma_m)^2,
        r_j = ((1 + theta)^-1/2 - 1) / sigma_j
    over the training modes, C their covariance in those units (Delta + G G^T, G the
    reference's scatter rows, Delta = 1 - diag(G G^T), inverted directly here; the code whitens
    by the Woodbury form) (1-D minimisation here, eigen-solves in the code). A free scale
    (no prior) would take the 6 % within its +-10 % bound and leave the weighing nothing; with
    the prior, truncated at 3 sigma_m = 3.708 %, the weighing and prior rows keep at least their
    own minimum 0.06^2 / ((0.005 W / W0)^2 + sigma_m^2) = 19.9 (the frequencies and the
    truncation only add to it), and theta sits on its 3 sigma_m bound: flagged."""
    problem, ref, w0 = _chain_problem(tmp_path, 1.06)
    w, sd_m = 1.06 * w0, problem.prior[0]
    sigma = ref.frequency_sigma[ref.train]
    g = ref.scatter_rows
    c_inv = np.linalg.inv(np.diag(1.0 - np.sum(g ** 2, axis=1)) + g @ g.T)

    def chi2(t):
        r_f = ((1.0 + t) ** -0.5 - 1.0) / sigma
        return r_f @ c_inv @ r_f + (((1.0 + t) * w0 - w) / (0.005 * w)) ** 2 + (t / sd_m) ** 2

    hand = minimize_scalar(chi2, bounds=(-3 * sd_m, 3 * sd_m), method="bounded",
                           options={"xatol": 1e-9})
    assert problem.bounds[0] == pytest.approx(3 * 0.0123603, rel=1e-5)
    cal = calibrate(problem)
    assert cal.theta[0] == pytest.approx(hand.x, abs=2e-4)
    assert cal.chi2 == pytest.approx(hand.fun, rel=1e-2)
    kept = cal.evaluations[0].mass[0] ** 2 + (cal.theta[0] / sd_m) ** 2
    floor = 0.06 ** 2 / ((0.005 * w / w0) ** 2 + sd_m ** 2)
    assert floor == pytest.approx(19.9, abs=0.05)
    assert kept >= floor * (1.0 - 1e-6)
    assert cal.theta[0] == pytest.approx(3 * sd_m, rel=1e-6)   # the data want ~5 %
    assert any("mass sits on its bound" in flag for flag in cal.flags)
