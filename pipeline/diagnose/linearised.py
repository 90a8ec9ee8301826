"""A refitted effect linearised at its fit: its Jacobian and how well the data determine it.

Symbols, as in :mod:`pipeline.diagnose.screen`: x (npar,) the effect's parameters, theta
(n_theta,) the nominal parameters, r (n_data,) the training residual, each entry divided by its
standard deviation (:mod:`pipeline.diagnose.evidence`), so that chi^2 = r^T r; J = d r / d (x,
theta) (n_data, npar + n_theta): x's columns by forward differences with the pairing of the fit
held (:func:`pipeline.diagnose.calibrate.forward_columns`), theta's the calibration's
(``jacobian_theta``, as the refit takes them); c >= 1 the round's modal dispersion
(:func:`pipeline.diagnose.verdict.round_scores`: chi2_modal / c + chi2_stated is the score the
verdict compares, so the modal rows count 1 / c).

Standard errors. Near the fit chi2_modal / c + chi2_stated ~ const + d^T F d with F = J^T W J,
W = diag(1 / c on the modal rows, 1 on the stated ones): the Fisher information of the weighted
least-squares problem, and Cov(x, theta) = F^-1 (the Gauss-Newton covariance; with c it is the
quasi-likelihood covariance, Burnham & Anderson 2002 sec. 6.2, McCullagh & Nelder 1989 sec.
9.2). The nominal parameters are estimated with the effect, so an effect parameter's error is
the diagonal of the full inverse (theta profiled), sigma_k = sqrt((F^-1)_kk). A direction of F
the data do not see (eigenvalue below ``UNSEEN`` of the largest, on the parameters scaled to
order one) has no error bound: a parameter with a share in it gets sigma = inf ("not
determined": its value is where the fit left it, not what the data say).
"""
from __future__ import annotations

import numpy as np

from pipeline.diagnose.calibrate import THETA_SCALE, Problem, forward_columns, pairings
from structures.common.errors import InputError, SolverError

#: Forward-difference step of an effect parameter, relative to its scale in the refit (the larger
#: of its reference size and its starting value).
FD_STEP = 1e-3
#: Eigenvalue of the scaled information, relative to its largest, below which a direction is not
#: seen by the data (module docstring): far above the round-off of a forward difference
#: (FD_STEP^2 ~ 1e-6 of a column's size squared) and below any curvature a fit can use.
UNSEEN = 1e-10


def effect_jacobian(problem: Problem, effects, fit, jacobian_theta) -> tuple:
    """The training residual of a refitted effect and its Jacobian at the fit.

    Parameters
    ----------
    problem : Problem
    effects : sequence of (Candidate, values) already in the model.
    fit : Refitted, with a candidate.
    jacobian_theta : (n_data, n_theta) d r / d theta.

    Returns
    -------
    jac : (n_data, npar + n_theta) d r / d (x, theta), x's columns stepped by FD_STEP of
        ``size`` toward the inside of the upper bounds, the fit's pairing held.
    r : (n_data,) the residual at the fit.
    size : (npar,) each parameter's scale, max(|reference|, |x|).
    """
    cand, x = fit.candidate, np.asarray(fit.values, float)
    r = problem.residual(fit.theta, fit.evaluations)
    size = np.maximum(np.abs(np.asarray(cand.reference, float)), np.abs(x))
    paired = pairings(fit.evaluations)

    def residual(values):
        evs = problem.evaluate(fit.theta, tuple(effects) + ((cand, values),), paired)
        return problem.residual(fit.theta, evs)

    cols = forward_columns(residual, x, FD_STEP * size, cand.upper, r)
    return np.column_stack(cols + [np.asarray(jacobian_theta, float)]), r, size


def parameter_errors(jac, modal, c: float, scale) -> np.ndarray:
    """Standard errors of every parameter of a weighted least-squares fit (module docstring).

    Parameters
    ----------
    jac : (n_data, n) d r / d p.
    modal : (n_data,) bool, the modal rows (weighted 1 / c).
    c : float >= 1, the modal dispersion.
    scale : (n,) positive sizes of the parameters (F is eigen-decomposed on p / scale).

    Returns
    -------
    (n,) sigma_k = sqrt((F^-1)_kk); inf where a direction the data do not see has a share.
    """
    jac, scale = np.asarray(jac, float), np.asarray(scale, float)
    weight = np.where(np.asarray(modal, bool), 1.0 / np.sqrt(c), 1.0)
    scaled = jac * weight[:, None] * scale[None, :]
    lam, vec = np.linalg.eigh(scaled.T @ scaled)                # F on the scaled parameters
    seen = lam > UNSEEN * max(float(lam.max()), np.finfo(float).tiny)
    share = np.sum(vec[:, ~seen] ** 2, axis=1)                 # each parameter's unseen part
    var = np.sum(vec[:, seen] ** 2 / lam[seen], axis=1)
    return np.where(share > np.sqrt(UNSEEN), np.inf, np.sqrt(var) * scale)


def standard_errors(problem: Problem, effects, fit, c: float, *,
                    jacobian_theta) -> np.ndarray | None:
    """(npar,) standard errors of a refitted effect's parameters, the nominal parameters
    estimated with them (module docstring; inf: not determined by the training data); None
    when a model stepped from the fit cannot be analysed (a mechanism), the errors then not
    estimated.

    Parameters
    ----------
    problem : Problem
    effects : sequence of (Candidate, values) already in the model.
    fit : Refitted, with a candidate.
    c : float, the round's modal dispersion.
    jacobian_theta : (n_data, n_theta) d r / d theta.
    """
    try:
        jac, _, size = effect_jacobian(problem, effects, fit, jacobian_theta)
    except (SolverError, InputError):
        return None
    scale = np.concatenate([size, np.full(jac.shape[1] - size.size, THETA_SCALE)])
    return parameter_errors(jac, problem.modal_rows(), c, scale)[:size.size]
