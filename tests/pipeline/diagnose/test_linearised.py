"""Standard errors of a named effect (:mod:`pipeline.diagnose.linearised`): the kernel against the
closed form of a linear least-squares problem, and on the frame against exact reanalysis (the
profile chi^2 rises by c along one standard error)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from pipeline.diagnose import refit
from pipeline.diagnose.apply import apply_effect
from pipeline.diagnose.calibrate import Problem
from pipeline.diagnose.effects import candidates
from pipeline.diagnose.linearised import effect_jacobian, parameter_errors, standard_errors
from pipeline.diagnose.screen import Screened
from structures.bdf import read_model
from tests.pipeline.diagnose.perfect_frame import perfect_reference
from tests.pipeline.diagnose.truth import frame


def test_parameter_errors_are_the_weighted_least_squares_covariance():
    """r = J p + e with var(e_i) = c on the modal rows, 1 on the others: Cov(p) =
    (J^T W J)^-1, W = diag(1 / c, 1) (Seber & Wild 1989 sec. 2.1), whatever the scale."""
    rng = np.random.default_rng(3)
    jac = rng.normal(size=(40, 3)) * np.array([1.0, 30.0, 0.1])
    modal = np.arange(40) < 30
    c = 4.0
    w = np.where(modal, 1.0 / c, 1.0)
    expected = np.sqrt(np.diag(np.linalg.inv(jac.T @ (w[:, None] * jac))))
    kept = jac.copy()
    for scale in (np.ones(3), np.array([1.0, 1.0 / 30.0, 10.0]), np.array([5.0, 7.0, 0.1])):
        assert parameter_errors(jac, modal, c, scale) == pytest.approx(expected, rel=1e-9)
    assert np.array_equal(jac, kept)                             # the input is not modified


def test_a_parameter_the_data_do_not_see_has_no_error_bound():
    """A zero column (a parameter no residual depends on) and two columns that move the
    residual alike (only their sum is seen): inf for those, the others as without them."""
    rng = np.random.default_rng(4)
    jac = rng.normal(size=(25, 2))
    modal = np.ones(25, bool)
    alone = parameter_errors(jac, modal, 1.0, np.ones(2))
    blind = parameter_errors(np.column_stack([jac, np.zeros(25)]), modal, 1.0, np.ones(3))
    assert blind[:2] == pytest.approx(alone, rel=1e-9) and np.isinf(blind[2])
    twins = parameter_errors(np.column_stack([jac, jac[:, 1]]), modal, 1.0, np.ones(3))
    assert np.isfinite(twins[0]) and np.isinf(twins[1:]).all()


def test_standard_error_is_where_the_exact_chi2_rises_by_one(tmp_path):
    """The frame with 5 % of its mass hung at tail grid 4004 (a perfect test: c = 1), the mass
    refitted there with the nominal parameters held: moving the mass by one standard error, the
    inertia to its best value for that mass (the profile, from the same information matrix),
    raises the exact chi^2 (every configuration reanalysed) by 1 within 10 %."""
    model = read_model(frame.write_frame(tmp_path))
    cand = next(c for c in candidates(model, ("lumped_mass",)) if c.label == "grid 4004")
    truth = np.array([0.05, 2.0e-4])
    _, ref = perfect_reference(apply_effect(model, cand, truth), model)
    problem = Problem.build([ref], [model], 0.03)
    theta0 = np.zeros(len(problem.names))
    r0 = problem.residual(theta0, problem.evaluate(theta0))
    no_theta = np.zeros((r0.size, theta0.size))
    row = Screened(cand, truth * 0.9, 0.0, 0.0, np.zeros((r0.size, 2)))
    fit = refit.refit(problem, theta0, (), row, n_data=r0.size, jacobian_theta=no_theta,
                       max_nfev=refit.POLISH_NFEV, ftol=1e-12)
    fit = replace(fit, theta=theta0)                             # the nominal parameters held
    sigma = standard_errors(problem, (), fit, 1.0, jacobian_theta=no_theta)
    assert np.all(np.isfinite(sigma)) and sigma[0] < 0.1 * fit.values[0]
    jac, r, _ = effect_jacobian(problem, (), fit, no_theta)
    cov = np.linalg.inv(jac[:, :2].T @ jac[:, :2])
    step = sigma[0] * cov[:, 0] / cov[0, 0]                      # the mass +1 sigma, profiled

    def chi2(values):
        return float(np.sum(problem.residual(theta0, problem.evaluate(
            theta0, ((cand, values),))) ** 2))

    base = chi2(fit.values)
    for sign in (1.0, -1.0):
        assert chi2(fit.values + sign * step) - base == pytest.approx(1.0, rel=0.1)


def test_no_standard_errors_where_a_stepped_model_cannot_be_analysed(monkeypatch):
    """A step of a parameter that makes a mechanism (the solver refuses the model): the errors
    are not estimated (None), and the diagnosis goes on."""
    from pipeline.diagnose import linearised
    from structures.common.errors import SolverError

    def refuse(*args, **kwargs):
        raise SolverError("mechanism")

    monkeypatch.setattr(linearised, "effect_jacobian", refuse)
    assert standard_errors(None, (), None, 1.0, jacobian_theta=None) is None
