"""Screening of candidate effects and the bounded refit of the best.

Every candidate is screened by an exact or near-exact analysis of its changed model at several
sizes, because no kind acts linearly at the sizes a real effect has (a first-order secant through
one step predicted the wrong size, or none, for masses, tapers, bows and springs alike; numbers in
each route below). The result of a candidate is (S, exact): ``exact`` the best size x* and its
chi^2 when the route finds them (ladders, line searches), and S a matrix with r0 + S m(x) the
model's training residual at x (the secant (r(x*) - r0) / x* with m(x) = x for a ladder, the
second-order model of :mod:`pipeline.diagnose.quadratic` otherwise); r is the training residual of
every configuration (:mod:`pipeline.diagnose.evidence`). The routes:

- *ladder* (``joint_flexibility``, whose compliance changes the constraints and acts far from
  linearly: a joint's local mode falls as 1 / sqrt(compliance) and sweeps through the measured
  modes; sampled at rotation 0, the refit frees the rotation): reanalysis at every size of
  :data:`LADDER` (quarter decades of the parameter's range) and at the eighth decades either
  side of the best (:data:`LADDER_REFINE`); the best size x* and its exact chi^2 are the
  candidate's screening result, the secant (r(x*) - r0) / x* its signature. The rungs are
  analysed on one Craig-Bampton basis per joint and configuration
  (:mod:`pipeline.diagnose.ladder`, models of up to :data:`structures.modal.DENSE_LIMIT` free
  DOFs) and the best size x* again exactly (the exact ladder when that fails). The one-sided
  variants of a joint (one dependent grid on its spring) are screened only for the
  ``ONE_SIDED_TOP`` best whole joints (cost per joint and configuration: two assemblies, one
  truncated eigen-solution, 23 small ones and one exact reanalysis). A joint whose hung grids
  carry nothing (:func:`pipeline.diagnose.joints.hangs_nothing`, e.g. massless sensor or
  attachment points on an RBE2) changes no mode at any size: it is not sampled (size the
  smallest rung, chi^2 the current one, signature zero).
- *Ritz ladder* (:data:`RITZ_KINDS`; ``boundary_stiffness``: a grounded spring turns a
  rigid-body motion into an elastic mode whose frequency rises as sqrt(k), and the modes it
  passes veer and mix, so chi^2
  over k has valleys a few percent of k wide; the frame's seed 8 of the blind study: exact chi^2
  1.6e3 at k = 0.124, 1.3e4 at 0.13, 1.9e4 at 0.117, the secant at 0.1 misses it): the modes on
  one Ritz basis per configuration and round (:mod:`pipeline.diagnose.grounded`, the current
  modes and the spring's residual attachment vector; K(k) is a rank-one change, rank two for a
  mirror pair, frequencies
  within 2e-6 of exact reanalysis) at the sizes of :func:`pipeline.diagnose.grounded.ladder_sizes`
  (quarter decades over the top three, intervals halved while some mode turns by more than ~18
  degrees across them, down to 1/128 decade); the best rung's size and chi^2 on the basis are the
  candidate's screening result, the secant to it its signature (cost on the frame, 264
  one-sided candidates and ~5,900 rungs: ~5 s a round on a shared core, against 0.25 s for the
  secants; the 114 mirror pairs add about as much again). ``lumped_mass`` likewise (M(x) is a
  rank-three change, rank six for a pair; the mass's own mode falls through the measured ones as
  it grows): its rungs on the same bases (:func:`pipeline.diagnose.grounded.reduce_mass`,
  frequencies within 4e-6 of exact reanalysis up to 10 % of the model's mass).

- *quadratic* (:data:`QUADRATIC_KINDS`, a member's bow: its stiffness changes to second order,
  its couplings to first, so no secant is right at more than one size; a member's taper: its
  section's I ~ s^4, and the modes' response is far from linear at a real taper's sizes, of
  either sign): the second-order model
  r(x) = r0 + S monomials(x) of :mod:`pipeline.diagnose.quadratic` from exact reanalyses at
  h_k, 2 h_k and h_k + h_l for a bow, +-2 h_k and 2 h_k + 2 h_l for a taper (the first-order
  eigenvalue perturbation would miss the (phi_k^T dK_1 phi_j)^2 / (lambda_j - lambda_k) term of
  the couplings, the same order in the bow as the stiffness change; samples shared by a
  member's four quadrant candidates), fitted within the sampled span; the
  :data:`pipeline.diagnose.quadratic.LINE_SEARCH_TOP` best of each kind then get an exact line
  search to their bounds (:func:`pipeline.diagnose.quadratic.line_search`), whose best size and
  exact chi^2 are their screening result.

**Ranking** (:func:`screen`): a candidate's best size and chi^2 are ``exact``, else the
quadratic model's fit within its bounds and sampled span; the candidates are ranked by the drop
of chi^2.

**Refit**: bounded nonlinear least squares with reanalysis (``scipy.optimize.least_squares``) of
the effect's parameters together with the nominal parameters (:mod:`pipeline.diagnose.calibrate`),
started at the screening's best size and its fractions :data:`REFIT_START`; ranked by
BIC = chi^2 + p ln n (Schwarz 1978).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import least_squares

from pipeline.diagnose.calibrate import (THETA_SCALE, Problem, forward_columns, memoised,
                                         pairings)
from pipeline.diagnose.evidence import evaluate, evaluate_modes
from pipeline.diagnose.fit_statistics import bic, chi_square
from pipeline.diagnose.grounded import (SPRING_LADDER, ladder_sizes, reduce_mass, reduce_spring,
                                        spring_basis)
from pipeline.diagnose.joints import hangs_nothing
from pipeline.diagnose.ladder import reduce_joint
from pipeline.diagnose.linearised import FD_STEP, effect_jacobian
from pipeline.diagnose.mirror import sites
from pipeline.diagnose.quadratic import (coefficients, line_searches, monomials, quadratic_fit,
                                         sample_points, secant)
from pipeline.diagnose.verdict import on_bound
from structures.common.errors import InputError, SolverError

#: Kinds screened on the ladder of sizes by reanalysis (they change the constraint equations).
LADDER_KINDS = ("joint_flexibility",)
#: Kinds screened on a ladder of sizes on the Ritz basis of :mod:`pipeline.diagnose.grounded`
#: (a rank-q change of K or of M at fixed grids).
RITZ_KINDS = ("boundary_stiffness", "lumped_mass")
#: Kinds screened with the quadratic model of :mod:`pipeline.diagnose.quadratic`, and its
#: sampling scheme: a member's bow (stiffness ~ bow^2, couplings ~ bow; the effects.py
#: docstring; its quadrant fixes the signs) and a member's taper (I ~ s^4, either sign).
QUADRATIC_KINDS = {"member_curvature": "one_sided", "member_taper": "centred"}
#: One-sided joint candidates (detail ``dependent``) are screened for the rigid elements of this
#: many best whole-joint candidates only (a one-sided joint is a variant of its whole joint).
ONE_SIDED_TOP = 5
#: Sizes of a ladder-screened parameter, as fractions of its upper bound (quarter decades over
#: the top five decades: the chi^2 of a joint has narrow valleys where its local modes meet the
#: measured ones, a factor ~2 wide); the best rung's eighth-decade neighbours are tried next.
LADDER = tuple(10.0 ** (-0.25 * np.arange(21)[::-1]))
#: Refinement of the best rung (factors).
LADDER_REFINE = (10.0 ** -0.125, 10.0 ** 0.125)
#: A rung's chi^2 below the best one's by less than this fraction is round-off, not a better size
#: (a joint whose hung grids carry no mass changes nothing: every rung gives the same chi^2 to
#: ~1e-13, and the smallest size is kept rather than whichever rounds lowest).
LADDER_ROUNDOFF = 1e-9
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
class Screened:
    """One candidate after the screening.

    Attributes
    ----------
    candidate : Candidate
    values : (npar,) best bounded size found by the screening.
    chi2 : float, the screening's chi^2 at ``values`` (exact or on the Ritz or Craig-Bampton
        basis for a ladder or a line search, of the quadratic model otherwise).
    drop : float, chi^2 of the current model minus ``chi2``.
    signature : (n_data, npar) signature S; the secant to ``values`` (S values = the
        residual's change there) for a ladder and for :data:`QUADRATIC_KINDS` (of the quadratic
        model, or exact after a line search).
    """

    candidate: object
    values: np.ndarray
    chi2: float
    drop: float
    signature: np.ndarray


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


def signatures(problem: Problem, theta, effects, evaluations, candidates, *, progress=None):
    """The screening analyses of every candidate (see the module docstring).

    Parameters
    ----------
    problem : Problem
    theta : (n_theta,) nominal parameters of the current model.
    effects : sequence of (Candidate, values) already in the model.
    evaluations : list of Evaluation of the current model.
    candidates : sequence of Candidate
    progress : callable(str), optional

    Returns
    -------
    r0 : (n_data,) current training residual.
    list of (Candidate, S (n_data, npar or n_columns), exact); ``exact`` is (values (npar,),
    chi2) of a ladder-screened or line-searched candidate's best size, else None. Candidates
    that cannot be applied to every configuration are left out (named in ``skipped``).
    skipped : list of str
    """
    from pipeline.diagnose.effects import apply_effect

    models = [problem.model(i, theta, effects) for i in range(len(problem.refs))]
    r0 = problem.residual(theta, evaluations)
    prior = problem.prior_residual(theta)                                  # a candidate keeps theta

    def residual(cand, step):
        """Training residual of the candidate at ``step`` by exact reanalysis."""
        return np.concatenate([evaluate(ref, apply_effect(model, cand, step)).vector(ref)
                               for ref, model in zip(problem.refs, models)] + [prior])

    def reduced(cand):
        """size -> training residual on the candidate's Craig-Bampton bases, or None."""
        bases = []
        for ref, model in zip(problem.refs, models):
            sensors = ref.sensor_index if ref.has_shapes else np.zeros(0, int)
            bases.append(reduce_joint(model, cand, sensors, ref.nmodes))
            if bases[-1] is None:
                return None

        return lambda size: on_bases(bases, size)

    def on_bases(bases, size):
        """Training residual of the rung ``size`` on one reduced model per configuration."""
        parts = []
        for ref, basis in zip(problem.refs, bases):
            modes, shapes = basis.modes(size)
            e1 = evaluate_modes(ref, modes["frequency"].values,
                                shapes if ref.has_shapes else None, basis.properties(size),
                                modes=modes)
            parts.append(e1.vector(ref))
        return np.concatenate(parts + [prior])

    springs = []

    def ritz_bases():
        """The Ritz bases of :mod:`pipeline.diagnose.grounded`, one per configuration and
        round, shared by the grounded springs and the masses."""
        if not springs:
            bases = [spring_basis(m, ref.sensor_index if ref.has_shapes else np.zeros(0, int),
                                  ref.nmodes) for ref, m in zip(problem.refs, models)]
            springs.extend(bases)                   # all configurations or none (a failure)
        return springs

    def ritz_ladder(cand):
        """A grounded spring's or a mass's rungs (:func:`pipeline.diagnose.grounded.ladder_sizes`)
        on the Ritz bases."""
        if cand.kind == "lumped_mass":
            reds = [reduce_mass(b, cand) for b in ritz_bases()]
        else:
            reds = [reduce_spring(b, cand, cand.upper[0] * SPRING_LADDER[0])
                    for b in ritz_bases()]
        return _ladder(cand, r0, residual, lambda size: on_bases(reds, size),
                       sizes=ladder_sizes(reds, cand.upper[0]))

    def one_sided(cand):
        return cand.kind in LADDER_KINDS and cand.get("dependent") is not None

    out, skipped = [], []
    samples = {}

    def shared(cand, step):
        """Exact residual of a quadratic-kind size, once per kind, location and size."""
        key = (cand.kind, cand.location, tuple(np.asarray(step, float).tolist()))
        if key not in samples:
            samples[key] = residual(cand, step)
        return samples[key]

    def run(cands):
        for n, cand in enumerate(cands):
            if progress is not None and n % 50 == 0:
                progress(f"screening {n}/{len(cands)}")
            try:
                if cand.kind in LADDER_KINDS and all(
                        hangs_nothing(m, site.location.elements[0], site.get("dependent"))
                        for m in models for site in sites(cand)):
                    out.append((cand, np.zeros((r0.size, len(cand.parameters))),
                                (_first(cand, cand.upper[0] * LADDER[0]), chi_square(r0))))
                    continue
                if cand.kind in RITZ_KINDS:
                    out.append(ritz_ladder(cand))
                    continue
                if cand.kind in LADDER_KINDS:
                    out.append(_ladder(cand, r0, residual, reduced(cand)))
                    continue
                scheme = QUADRATIC_KINDS[cand.kind]                # the other kinds
                sampled = [shared(cand, step) for step in sample_points(cand.reference, scheme)]
                out.append((cand, coefficients(r0, sampled, cand.reference, scheme), None))
            except (InputError, SolverError) as exc:
                skipped.append(f"{cand.label}: {exc}")

    run([c for c in candidates if not one_sided(c)])
    whole = sorted((exact[1], cand.location.elements[0]) for cand, _, exact in out
                   if cand.kind in LADDER_KINDS and cand.get("sites") is None)
    best = {eid for _, eid in whole[:ONE_SIDED_TOP]}
    run([c for c in candidates if one_sided(c) and c.location.elements[0] in best])
    line_searches(out, r0, residual, QUADRATIC_KINDS)
    return r0, out, skipped


def _first(cand, size: float) -> np.ndarray:
    """(npar,) parameters of a ladder rung: its first parameter at ``size``, the others at 0
    (a joint's ``rotation``: the reference ratio)."""
    return np.r_[size, np.zeros(len(cand.parameters) - 1)]


def _ladder(cand, r0, residual, approximate=None, sizes=None) -> tuple:
    """(Candidate, secant S, (x*, chi2*)) of a candidate sampled on :data:`LADDER` along its
    first parameter, the others at 0 (sizes whose model cannot be analysed are passed over).
    ``approximate`` (size -> residual, :mod:`pipeline.diagnose.ladder`) samples the rungs; x* is
    then analysed again exactly, and the exact ladder runs instead when that fails. ``sizes``
    (a grounded spring's rungs, :func:`pipeline.diagnose.grounded.ladder_sizes`) replaces the
    ladder and its refinement, and x* keeps the ``approximate`` residual (the Ritz basis's
    accuracy, grounded.py)."""
    best, failure = None, None

    def rung(size):
        nonlocal best, failure
        try:
            r = approximate(size) if approximate is not None else \
                residual(cand, _first(cand, size))
        except (InputError, SolverError) as exc:
            failure = exc
            return
        if best is None or chi_square(r) < best[2] * (1.0 - LADDER_ROUNDOFF):
            best = (size, r, chi_square(r))

    for size in cand.upper[0] * np.asarray(LADDER) if sizes is None else sizes:
        rung(size)
    if best is None:
        raise failure
    for size in best[0] * np.array(LADDER_REFINE) if sizes is None else ():
        if size <= cand.upper[0]:
            rung(size)
    size = best[0]
    if approximate is not None and sizes is None:
        try:
            r = residual(cand, _first(cand, size))
        except (InputError, SolverError):
            return _ladder(cand, r0, residual)
        best = (size, r, chi_square(r))
    size, r, chi2 = best
    return cand, secant(r0, r, _first(cand, size)), (_first(cand, size), chi2)


def screen(r0, signed) -> list:
    """The best size of every (Candidate, S, exact) of :func:`signatures`: ``exact`` (x, chi2)
    of a ladder or a line search as it is, else the quadratic model's fit; list of Screened
    sorted by decreasing drop."""
    chi0 = chi_square(r0)
    rows = []
    for cand, s, exact in signed:
        if exact is not None:
            x, chi2 = exact
        else:
            x, chi2 = quadratic_fit(r0, s, cand.reference, cand.lower, cand.upper,
                                    QUADRATIC_KINDS[cand.kind])
            s = secant(r0, np.asarray(r0) + s @ monomials(x), x)
        rows.append(Screened(cand, x, chi2, chi0 - chi2, s))
    rows.sort(key=lambda row: -row.drop)
    return rows


def pick_for_refit(rows, count: int) -> list:
    """The best screened candidate of every kind, then the next best, ``count`` in all
    (distinct kinds first, so that the runner-up of another kind is always refitted)."""
    chosen, kinds = [], set()
    for row in rows:
        if row.candidate.kind not in kinds and row.drop > 0:
            chosen.append(row)
            kinds.add(row.candidate.kind)
    chosen = chosen[:count]
    for row in rows:
        if len(chosen) >= count:
            break
        if row not in chosen and row.drop > 0:
            chosen.append(row)
    return chosen


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
