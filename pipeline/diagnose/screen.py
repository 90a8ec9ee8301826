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
  exact chi^2 are their screening result. A taper is also analysed exactly on the grid of
  :data:`GRID_KINDS` (scale -0.2 .. 0.2 by 0.1, taper +-0.3 and +-0.6: 20 reanalyses) and at
  the model's fit, for the :data:`GRID_TOP` tapers whose model fits best, before the line
  searches, and the best of these, when it fits better than no effect, is its screening
  result instead (:func:`grid_searches`; the :data:`GRID_REFINE_TOP` best are refined,
  :func:`grid_refinements`): a short member's local modes cross the measured ones and its
  chi^2 has narrow, rugged valleys that the model does not follow (the frame's blind-study
  taper seed 13, the truth's member: chi^2 958 without an effect, 785 at the grid point
  (-0.1, -0.3), 661 at (-0.10, -0.44), 356 at (-0.09, -0.44), 2125 at (0, -0.3), where the
  model predicts 718 at (0, -0.31) and its line search finds no drop).

**Ranking** (:func:`screen`): a candidate's best size and chi^2 are ``exact``, else the
quadratic model's fit within its bounds and sampled span; the candidates are ranked by the drop
of chi^2. The best are then refitted (:mod:`pipeline.diagnose.refit`).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from pipeline.diagnose.calibrate import Problem
from pipeline.diagnose.evidence import evaluate, evaluate_modes
from pipeline.diagnose.fit_statistics import chi_square
from pipeline.diagnose.grounded import (SPRING_LADDER, ladder_sizes, reduce_mass, reduce_spring,
                                        spring_basis)
from pipeline.diagnose.joints import hangs_nothing
from pipeline.diagnose.ladder import reduce_joint
from pipeline.diagnose.mirror import sites
from pipeline.diagnose.quadratic import (coefficients, line_searches, monomials, quadratic_fit,
                                         sample_points, secant)
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
#: Exact grids of (scale, taper) sampled for a member's taper besides its quadratic model: a
#: short member's local modes cross the measured ones and its chi^2 has narrow valleys the
#: quadratic model misses (the frame's blind-study taper seed 13).
GRID_KINDS = {"member_taper": tuple((s, t) for s in (-0.2, -0.1, 0.0, 0.1, 0.2)
                                    for t in (-0.6, -0.3, 0.3, 0.6))}
#: Spacing of each parameter in a :data:`GRID_KINDS` grid. The best points of the
#: :data:`GRID_REFINE_TOP` candidates of each kind whose grid point fits best are refined on their
#: neighbours at half, then a quarter of it (the ladder's refinement of its best rung, in two
#: parameters): the valleys are narrower than the grid.
GRID_SPACING = {"member_taper": (0.1, 0.3)}
GRID_REFINE_TOP = 4
#: Candidates of each kind of :data:`GRID_KINDS` (best quadratic-model fits first) analysed on
#: its grid. The shipped example's diagnosis with and without the grid, side by side on one core
#: each under cProfile: its three screenings 851 s against 766 s, the whole diagnosis 1598 s
#: against 1520 s (about 230 analyses a round of 0.13 s each). Gridding every taper instead (the
#: frame's ~500 tapers and mirror pairs) costs a frame case 335 s against 246 s.
GRID_TOP = 8
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
    from pipeline.diagnose.apply import apply_effect

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
    grid_searches(out, r0, shared)
    grid_refinements(out, r0, shared)
    line_searches(out, r0, residual, QUADRATIC_KINDS)
    return r0, out, skipped


def _grid_best(cand, r0, s, shared):
    """(x, chi2, r) of the exact best of :data:`GRID_KINDS`' grid and of the quadratic model's
    fit (analysed exactly: the model's own chi^2 there can be far off, e.g. 718 predicted, 2125
    exact) when it fits better than the model without the candidate, else None (the quadratic
    route and its line search). Points whose model cannot be analysed are passed over."""
    x_q, _ = quadratic_fit(r0, s, cand.reference, cand.lower, cand.upper,
                           QUADRATIC_KINDS[cand.kind])
    best = None
    for point in (*GRID_KINDS[cand.kind], x_q):
        x = np.clip(np.asarray(point, float), cand.lower, cand.upper)
        try:
            r = shared(cand, x)
        except (InputError, SolverError):
            continue
        if best is None or chi_square(r) < best[1]:
            best = (x, chi_square(r), r)
    if best is None or best[1] >= chi_square(r0):
        return None
    return best


def grid_searches(out, r0, residual) -> None:
    """The exact grid (:func:`_grid_best`) of the :data:`GRID_TOP` entries of each kind of
    :data:`GRID_KINDS` in ``out`` (the screening's (Candidate, S, exact) list) whose quadratic
    model fits best; an entry whose grid finds a better fit than no effect is replaced in place
    by (Candidate, secant to x*, (x*, chi2*)). ``residual(cand, x)`` is the exact training
    residual."""
    for kind in GRID_KINDS:
        scheme = QUADRATIC_KINDS[kind]
        fits = sorted((quadratic_fit(r0, s, cand.reference, cand.lower, cand.upper, scheme)[1], i)
                      for i, (cand, s, exact) in enumerate(out)
                      if cand.kind == kind and exact is None)
        for _, i in fits[:GRID_TOP]:
            cand, s, _ = out[i]
            grid = _grid_best(cand, r0, s, residual)
            if grid is not None:
                out[i] = (cand, secant(r0, grid[2], grid[0]), grid[:2])


def grid_refinements(out, r0, residual) -> None:
    """Refine in place the grid points of the :data:`GRID_REFINE_TOP` best grid-screened entries
    of each kind of :data:`GRID_SPACING` in ``out`` (the screening's (Candidate, S, exact) list,
    ``exact`` (x, chi2) from :func:`_grid_best`): the 3^npar - 1 neighbours at half the grid's
    spacing, then at a quarter, each time moving to the best when it fits better; the entry
    becomes (Candidate, secant to x*, (x*, chi2*)). ``residual(cand, x)`` is the exact training
    residual (InputError or SolverError where the model cannot be analysed: passed over)."""
    for kind, spacing in GRID_SPACING.items():
        rows = sorted((exact[1], i) for i, (cand, _, exact) in enumerate(out)
                      if cand.kind == kind and exact is not None)
        for _, i in rows[:GRID_REFINE_TOP]:
            cand, _, (x, chi2) = out[i]
            r = residual(cand, x)
            for factor in (0.5, 0.25):
                h = factor * np.asarray(spacing, float)
                best = (chi2, x, r)
                for step in itertools.product((-1.0, 0.0, 1.0), repeat=h.size):
                    y = np.clip(x + h * np.asarray(step), cand.lower, cand.upper)
                    if not any(step) or np.array_equal(y, x):
                        continue
                    try:
                        ry = residual(cand, y)
                    except (InputError, SolverError):
                        continue
                    if chi_square(ry) < best[0]:
                        best = (chi_square(ry), y, ry)
                chi2, x, r = best
            out[i] = (cand, secant(r0, r, x), (x, chi2))


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
