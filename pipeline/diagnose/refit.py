"""The bounded refit of screened candidates (:mod:`pipeline.diagnose.screen`), its continuation
to convergence for the named effect, and the test of a parameter on its bound.

**Refit** (:func:`refit`): bounded nonlinear least squares with reanalysis
(``scipy.optimize.least_squares``) of the effect's parameters together with the nominal parameters
(:mod:`pipeline.diagnose.calibrate`), started at the screening's best size and its fractions
:data:`REFIT_START`; ranked by BIC = chi^2 + p ln n (Schwarz 1978). The named effect's fit is
continued to convergence (:func:`polish`, :func:`continued`), and a parameter the refit left on a
bound is tested for whether the data press against it (:func:`bound_release`).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import least_squares

from pipeline.diagnose.calibrate import THETA_SCALE, Problem, forward_columns, memoised, pairings
from pipeline.diagnose.fit_statistics import bic, chi_square
from pipeline.diagnose.linearised import FD_STEP, effect_jacobian
from pipeline.diagnose.screen import Screened
from pipeline.diagnose.verdict import on_bound
from structures.common.errors import InputError, SolverError

#: Most iterations of one refit (started at the screening's best size, a few suffice).
REFIT_NFEV = 12
#: Most iterations of the named effect's final fit (:func:`polish`).
POLISH_NFEV = 60
#: The polish stops when an iteration lowers chi^2 by less than this fraction of it.
POLISH_FTOL = 1e-4
#: Residual at a trial point whose model cannot be analysed, relative to the starting residual.
PENALTY = 3.0
#: Fractions of the screening's best size at which the refit's start is analysed exactly: the
#: screening's model extrapolates its signature, and past a mode crossing (a mass or spring that
#: moves one mode through another changes the pairing) the exact chi^2 jumps; the refit starts at
#: the best of these (a backtracking line search, Nocedal & Wright 2006 sec. 3.1).
REFIT_START = (1.0, 0.5, 0.25)
#: Fractions of the unbounded Gauss-Newton step analysed by :func:`bound_release`.
RELEASE_STEPS = (1.0, 0.5, 0.25)
#: Share of a parameter's range by which :func:`bound_release` moves its non-zero bounds out.
RELEASE_WIDENING = 0.5



@dataclass(frozen=True)
class Refitted:
    """One candidate after the nonlinear refit.

    Attributes
    ----------
    candidate : Candidate, or None for "none" (the nominal parameters only).
    values : (npar,) fitted effect parameters.
    theta : (n_theta,) fitted nominal parameters.
    chi2, bic : float
    n_params : int, effect + nominal parameters.
    evaluations : list of Evaluation at the fit.
    """

    candidate: object
    values: np.ndarray
    theta: np.ndarray
    chi2: float
    bic: float
    n_params: int
    evaluations: list


def refit(problem: Problem, theta0, effects, row: Screened | None, *, n_data: int,
          jacobian_theta, max_nfev: int = REFIT_NFEV, starts=REFIT_START,
          ftol: float = 1e-8) -> Refitted | None:
    """Bounded nonlinear least squares of a candidate's parameters and the nominal parameters.

    The effect parameters' Jacobian columns are forward differences with reanalysis, the pairing
    of the point held (:func:`pipeline.diagnose.calibrate.forward_columns`); the nominal
    parameters' columns are ``jacobian_theta`` (n_data, n_theta), d r / d theta of the
    calibration (they change little with a small effect; this saves a reanalysis of every
    configuration per nominal parameter and iteration). ``row`` None refits the nominal
    parameters alone ("none"). The start is the screening's best size scaled by each of
    ``starts`` (default :data:`REFIT_START`), analysed exactly. At most ``max_nfev`` iterations
    (``scipy.optimize.least_squares``, trf, ``ftol``). A model that cannot be analysed at some
    trial point (a mechanism) costs ``PENALTY`` times the starting residual there; None when
    every start fails.
    """
    cand = None if row is None else row.candidate
    npar = 0 if cand is None else len(cand.parameters)
    size = np.maximum(np.abs(np.asarray(cand.reference, float)), np.abs(row.values)) if cand \
        else np.zeros(0)
    scale = np.concatenate([size, np.full(len(theta0), THETA_SCALE)])
    lo = np.concatenate([np.asarray(cand.lower, float) if cand else np.zeros(0),
                         -problem.bounds]) / scale
    hi = np.concatenate([np.asarray(cand.upper, float) if cand else np.zeros(0),
                         problem.bounds]) / scale
    start = np.concatenate([row.values if cand else np.zeros(0), np.asarray(theta0, float)])
    z0 = np.clip(start / scale, lo, hi)
    j_theta = np.asarray(jacobian_theta, float) * THETA_SCALE

    def split(z):
        x = z * scale
        extra = ((cand, x[:npar]),) if cand else ()
        return x[npar:], tuple(effects) + extra

    def residual(z, paired=None):
        theta, eff = split(z)
        evs = problem.evaluate(theta, eff, paired)
        return problem.residual(theta, evs), pairings(evs)

    start_fit = None
    for t in starts if cand else (1.0,):
        z_t = np.concatenate([z0[:npar] * t, z0[npar:]])
        try:
            fit_t = residual(z_t)
        except (SolverError, InputError):
            continue
        if start_fit is None or chi_square(fit_t[0]) < chi_square(start_fit[0]):
            z_start, start_fit = z_t, fit_t
    if start_fit is None:
        return None
    z0, r_start = z_start, start_fit[0]

    def attempt(z, paired=None):
        try:
            return residual(z, paired)
        except (SolverError, InputError):
            return PENALTY * r_start, None

    fun, at = memoised(attempt, {z0.tobytes(): start_fit})

    def jac(z):
        r, paired = at(z)
        cols = ([np.zeros_like(r)] * npar if paired is None else       # a mechanism: flat
                forward_columns(lambda y: attempt(y, paired)[0], z, np.full(npar, FD_STEP), hi, r))
        return np.column_stack(cols + [j_theta])

    z = z0
    if z0.size:
        z = least_squares(fun, z0, jac=jac, bounds=(lo, hi), method="trf",
                          max_nfev=max_nfev, ftol=ftol).x
    theta, eff = split(z)
    try:
        evs = problem.evaluate(theta, eff)
    except (SolverError, InputError):
        return None
    chi2 = chi_square(problem.residual(theta, evs))
    p = npar + len(theta0)
    return Refitted(cand, (z * scale)[:npar], theta, chi2, bic(chi2, p, n_data), p, evs)


def polish(problem: Problem, effects, fit: Refitted, *, n_data: int,
           jacobian_theta) -> Refitted:
    """The named effect's fit continued to convergence (:func:`refit` from ``fit``, at most
    :data:`POLISH_NFEV` iterations, stopping when an iteration lowers chi^2 by less than
    :data:`POLISH_FTOL` of it); ``fit`` itself when that does not lower chi^2.

    The refits that rank the candidates stop at :data:`REFIT_NFEV` iterations, enough to rank
    them; the effect added to the model, written out and judged by the gap is its best fit. On
    noise-free data (a hidden mass on a chain of masses, tests/pipeline/test_cmd_diagnose.py) 12
    iterations leave an RMS frequency error of 0.06 %, one that differs by 0.1 % between
    machines (their floating-point round-off takes the trust region elsewhere), and 40 reach
    1e-4 %.

    Parameters
    ----------
    problem : Problem
    effects : sequence of (Candidate, values) already in the model.
    fit : Refitted, with a candidate: the named effect's refit.
    n_data : int, training data (the BIC's n).
    jacobian_theta : (n_data, n_theta) d r / d theta, as in :func:`refit`.

    Returns
    -------
    Refitted
    """
    out = continued(problem, fit.theta, effects, fit.candidate, fit.values, n_data=n_data,
                    jacobian_theta=jacobian_theta)
    return out if out is not None and out.chi2 < fit.chi2 else fit


def continued(problem: Problem, theta0, effects, candidate, values, *, n_data: int,
              jacobian_theta) -> Refitted | None:
    """A candidate's fit, with the nominal parameters, continued to convergence from
    (``values``, ``theta0``): :func:`refit` with :data:`POLISH_NFEV` iterations at most and
    tolerance :data:`POLISH_FTOL` (:func:`polish`); None when the start cannot be analysed."""
    row = Screened(candidate, np.asarray(values, float), np.nan, 0.0, None)
    return refit(problem, theta0, effects, row, n_data=n_data, jacobian_theta=jacobian_theta,
                 max_nfev=POLISH_NFEV, starts=(1.0,), ftol=POLISH_FTOL)


def bound_release(problem: Problem, effects, fit: Refitted, *, jacobian_theta) -> tuple:
    """Whether the data want a refitted candidate's parameters that sit on a bound beyond it.

    A parameter on its bound (:func:`pipeline.diagnose.verdict.at_bound`) is the model-form
    signal only when the bound holds it there. A bounded refit of a few iterations
    (:data:`REFIT_NFEV`) can also stop on a bound the data do not press against (a flat valley).
    The test: the Gauss-Newton step without bounds from the fit, delta = -(J^T J)^+ J^T r over
    the effect's and the nominal parameters (the effect's columns by forward differences toward
    the inside of the bounds, the nominal ones ``jacobian_theta`` as in :func:`refit`), must move
    a parameter on a bound outward, and the exact chi^2 along it must fall below that along the
    same step with the parameters on their bounds held (so that what the refit's few iterations
    left to the nominal parameters or to a free effect parameter is not counted as the bound's
    gain): each step is analysed again at the fractions :data:`RELEASE_STEPS`, with every
    non-zero bound moved outward by :data:`RELEASE_WIDENING` of its parameter's range (a zero
    bound is "no effect" and stays), and the gain is the lowest chi^2 with the bounds held less
    the lowest released (the exact analyses, not the linearised gain, which overstates it where
    the effect acts far from linearly, as a taper's I ~ s^4).

    Parameters
    ----------
    problem : Problem
    effects : sequence of (Candidate, values) already in the model.
    fit : Refitted, with a candidate.
    jacobian_theta : (n_data, n_theta) d r / d theta.

    Returns
    -------
    outward : bool, the step moves a parameter on its bound outward.
    gain : float, the exact chi^2 the released step gains over the held one (>= 0; 0 when it
        is not outward).
    """
    cand, x = fit.candidate, np.asarray(fit.values, float)
    jac, r, _ = effect_jacobian(problem, effects, fit, jacobian_theta)
    delta = np.linalg.lstsq(jac, -r, rcond=None)[0]
    held = np.zeros(jac.shape[1], bool)
    outward = False
    for k in range(x.size):
        if on_bound(x[k], cand.lower[k], cand.upper[k]):
            held[k] = True
            up = abs(x[k] - cand.upper[k]) <= abs(x[k] - cand.lower[k])
            outward |= bool(delta[k] > 0 if up else delta[k] < 0)
    if not outward:
        return False, 0.0
    kept = np.zeros_like(delta)                             # the same step with the bounds held
    kept[~held] = np.linalg.lstsq(jac[:, ~held], -r, rcond=None)[0]
    lo, hi = np.asarray(cand.lower, float), np.asarray(cand.upper, float)
    span = RELEASE_WIDENING * (hi - lo)
    wide = replace(cand, lower=tuple(np.where(lo != 0.0, lo - span, 0.0)),
                   upper=tuple(np.where(hi != 0.0, hi + span, 0.0)))

    def lowest(step) -> float:
        best = chi_square(r)
        for t in RELEASE_STEPS:
            x_t = np.clip(x + t * step[:x.size], wide.lower, wide.upper)
            theta_t = np.clip(fit.theta + t * step[x.size:], -problem.bounds, problem.bounds)
            try:
                evs = problem.evaluate(theta_t, tuple(effects) + ((wide, x_t),))
            except (SolverError, InputError):
                continue
            best = min(best, chi_square(problem.residual(theta_t, evs)))
        return best

    return True, float(max(0.0, lowest(kept) - lowest(delta)))
