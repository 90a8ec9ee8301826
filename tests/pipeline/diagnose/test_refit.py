"""The bounded refit of a screened candidate (pipeline.diagnose.refit): a negative-quadrant
candidate from zero, the start at the best exactly analysed fraction of the screened size, and
the test of a pressed bound, on perfect tests of the frame."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from pipeline.diagnose import refit
from pipeline.diagnose.apply import apply_effect
from pipeline.diagnose.calibrate import Problem
from pipeline.diagnose.effects import candidates
from pipeline.diagnose.screen import Screened
from tests.pipeline.diagnose.perfect_frame import perfect_reference


def test_refit_of_a_negative_quadrant_candidate_from_zero(frame_reference):
    """A member_curvature candidate of the ``bow +y -z`` quadrant has a negative reference step
    for bow_2; refitted from a start with bow_2 = 0, its parameter scale is the step's size (not
    0, which made the bounds 0 / 0 and dropped the candidate). The refit returns finite
    parameters within the quadrant's bounds and a chi^2 no worse than the start's."""
    model, _, ref = frame_reference
    cand = next(c for c in candidates(model, ("member_curvature",)) if c.reference[1] < 0)
    problem = Problem.build([ref], [model], 0.03)
    theta0 = np.zeros(len(problem.names))
    evs = problem.evaluate(theta0)
    r0 = problem.residual(theta0, evs)
    start = np.array([0.02, 0.0])
    row = Screened(cand, start, 0.0, 0.0, np.zeros((r0.size, 2)))
    start_chi2 = float(np.sum(problem.residual(theta0, problem.evaluate(
        theta0, ((cand, start),))) ** 2))
    with np.errstate(divide="raise", invalid="raise"):
        fit = refit.refit(problem, theta0, (), row, n_data=r0.size,
                           jacobian_theta=np.zeros((r0.size, len(theta0))))
    assert fit is not None
    assert np.all(np.isfinite(fit.values))
    assert cand.lower[0] <= fit.values[0] <= cand.upper[0]
    assert cand.lower[1] <= fit.values[1] <= cand.upper[1] == 0.0
    assert fit.chi2 <= start_chi2 * (1 + 1e-9)


def test_refit_starts_at_the_best_exactly_analysed_fraction_of_the_screened_size(
        frame_reference, monkeypatch):
    """The model against its own modes: any added mass makes chi^2 grow, so of the screened size's
    fractions REFIT_START the smallest is the best start; with the iterations stubbed out
    (least_squares returning its start) the refit returns that start and its exact chi^2."""
    model, _, ref = frame_reference
    cand = next(c for c in candidates(model, ("lumped_mass",)) if c.get("sites") is None)
    problem = Problem.build([ref], [model], 0.03)
    theta0 = np.zeros(len(problem.names))
    r0 = problem.residual(theta0, problem.evaluate(theta0))
    start = np.array([0.04, 0.0])
    row = Screened(cand, start, 0.0, 0.0, np.zeros((r0.size, 2)))

    class Stopped:
        def __init__(self, x):
            self.x = x

    monkeypatch.setattr(refit, "least_squares", lambda fun, z0, **kw: Stopped(z0))
    fit = refit.refit(problem, theta0, (), row, n_data=r0.size,
                       jacobian_theta=np.zeros((r0.size, len(theta0))))
    best = min(refit.REFIT_START)
    assert fit.values == pytest.approx(best * start, rel=1e-12)
    exact = np.sum(problem.residual(theta0, problem.evaluate(theta0, ((cand, best * start),))) ** 2)
    assert fit.chi2 == pytest.approx(exact, rel=1e-12)
    chi2 = [np.sum(problem.residual(theta0, problem.evaluate(theta0, ((cand, t * start),))) ** 2)
            for t in refit.REFIT_START]
    assert np.argmin(chi2) == np.argmin(refit.REFIT_START)


@pytest.mark.parametrize("truth_mass, pressed", [(0.14, True), (0.10, False)])
def test_bound_release_tells_a_pressed_bound_from_a_touched_one(frame_reference, truth_mass,
                                                                pressed):
    """A perfect test made by the frame with a point mass at the tail grid 4004: 14 % of the
    model's mass, beyond the mass's bound 0.10, or 10 %, on it. Refitted from the bound, the mass
    sits on it both times; for 14 % the unbounded Gauss-Newton step from there moves it outward
    and the exact chi^2 along it falls by more than half of the fit's (measured: 2760 of 3524,
    the nominal model's 51850), for 10 % it gains nothing (measured 3e-16; limit 1e-3 of the
    nominal chi^2): the data press against the bound only when the truth lies beyond it."""
    model, _, ref0 = frame_reference
    cand = next(c for c in candidates(model, ("lumped_mass",)) if c.label == "grid 4004")
    wide = replace(cand, upper=(0.2, cand.upper[1]))                     # to make the truth
    _, ref = perfect_reference(apply_effect(model, wide, [truth_mass, 0.0]), model,
                                ref0.nmodes)
    problem = Problem.build([ref], [model], 0.03)
    theta0 = np.zeros(len(problem.names))
    r0 = problem.residual(theta0, problem.evaluate(theta0))
    row = Screened(cand, np.array([0.10, 0.0]), 0.0, 0.0, np.zeros((r0.size, 2)))
    jac = np.zeros((r0.size, len(theta0)))
    fit = refit.refit(problem, theta0, (), row, n_data=r0.size, jacobian_theta=jac)
    assert fit.values[0] == pytest.approx(0.10, abs=1e-3)
    outward, gain = refit.bound_release(problem, (), fit, jacobian_theta=jac)
    if pressed:
        assert outward and gain > 0.5 * fit.chi2
    else:
        assert gain < 1e-3 * np.sum(r0 ** 2)
