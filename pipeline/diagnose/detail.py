"""The named effect in more detail: its neighbouring joints, a joint's six CBUSH components, a
support spring's every free direction, and a mass's share on each grid around it.

Neighbouring joints. The two-parameter form names a joint: its kind and its location up to a
neighbour (a neighbour is not the named fit's rival, :func:`pipeline.diagnose.verdict.decide`).
It judges poorly between neighbouring joints. Its two compliances tie the six components into
two groups, so a detached variant of the joint or the next RBE2 can mimic an anisotropic joint
better than the right one. And the screening samples the compliance a quarter decade apart
(:data:`pipeline.diagnose.screen.LADDER`) on a rugged chi^2 (each local mode of the hung part
crosses a measured mode at its own compliance), so the right joint's valley can lie between two
rungs and the right joint is never refitted. The frame blind study's joint seeds at 6d63edc
(truths RBE2 7003, 7105 and 7005; chi^2 with two parameters -> in the detailed form):

- seed 3: the ladder ranks 7002 first and 7003 fifth. At the rung 3162 (rotation 0, on the
  calibrated model) 7002 has chi^2 660 and 7003 876, while 7003's valley, 632 at 2738, lies
  between that rung and the next below, 1778. 7003 was not refitted and 7002 was named
  (616.2 -> 484.3). Refitted from 7002's values, 7003 reaches 598.8 -> 367.2, and 7002's
  detached variant 2002-2202 591.3 -> 551.5;
- seed 0: 7104 (a neighbour) 426.8 -> 354.2 against the truth's 481.3 -> 164.0;
- seed 7: 7005 detached (2005-2205) 855.2 -> 251.1 against the truth's 1646.1 -> 237.9.

So the two-parameter chi^2 prefers a wrong neighbour in all three, and the detailed forms prefer
the truth in all three. Once a joint is named:

1. its neighbours of the same kind that were not refitted (single sites, at most
   :data:`NEIGHBOUR_REFITS`, by the screening's rank) are refitted, each from the best of the
   named fit's values with the compliance sampled a sixteenth of a decade apart about it
   (:data:`NEIGHBOUR_STARTS`, :func:`neighbour_refits`). Neighbouring joints hang similar
   parts, so their valleys lie at similar compliances;
2. the named fit and the :data:`NEIGHBOUR_DETAILED` refitted neighbours of least chi^2 are each
   put in the form of least BIC, two-parameter or detailed (below), and the best of these is
   added to the model (:func:`located`). The round's verdict stays the two-parameter one.

Components. The screening and the naming use a joint's two parameters (compliance and rotation,
:mod:`pipeline.diagnose.effects`): few enough for the information criterion to compare it with
a mass or a taper of two. A real joint's fittings are rarely alike in every direction (a flange
stiff in shear and soft in peel, a hinge soft about its own axis), and its hung part's local
modes, three translations and three rotations, then lie apart: one compliance per group of three
puts each group's modes at one frequency, and the held-out modes near them are paired with the
wrong one (the frame blind study's joint seeds at fccf93c: the named joint halves the held-out
frequency error but leaves cross-orthogonality off-diagonals of 0.7-0.9).

Once a joint is named, it is fitted again with one compliance per CBUSH component
(:func:`pipeline.diagnose.effects.directional`):

1. *Search.* chi^2 over the six compliances has many valleys (each local mode meets a measured
   one at its own compliance; a local least-squares fit from the named fit's values stays in the
   named fit's valley: on the frame's joint seed 2 it gains 6 of 919, where the truth's
   directional values give 446). So log10 c_p is searched globally, within
   :data:`SEARCH_DECADES` of the named values, by differential evolution (Storn & Price 1997,
   :func:`scipy.optimize.differential_evolution`, fixed seed) on the joint's Craig-Bampton basis
   with one stiffness matrix per component (:mod:`pipeline.diagnose.ladder`; sparse above
   :data:`structures.modal.DENSE_LIMIT` DOFs), the nominal parameters held at the named fit's.
2. *Refit.* The bounded least squares of :func:`pipeline.diagnose.refit.refit` (exact
   reanalysis, the nominal parameters free) from the search's best point.

The detail does not mend a wrong joint: on the frame's joint seed 3, before the neighbours were
compared, 7002's search ended at chi^2 484 (named 616), the held-out frequency error falling from
19.0 to 6.2 % but the largest cross-orthogonality off-diagonal rising from 0.81 to 0.91; the
truth's joint, 7003, in its detailed form gives 367, 2.3 % and 0.64 (its true compliances 386).

Support springs. The screening and the naming use a ``boundary_stiffness`` in one direction
(one parameter, :mod:`pipeline.diagnose.effects`), and a grid is named once, so the next round
does not offer the same grid's other directions (:func:`pipeline.diagnose.workflow.unnamed`). A
real support is rarely stiff in one direction only (a tyre, a bungee, a jack pad resist vertical
and lateral motion alike). So once a spring is named it is fitted again with one stiffness per
direction the grid's supports leave free (:func:`pipeline.diagnose.effects.every_direction`),
from the best of a grid of starts: the named stiffness kept, each other direction's at each of
:data:`SPRING_STARTS` times it (:func:`spring_start`, exact analyses), then the refit below. On
tests/pipeline/diagnose/test_detail.py's frame grounded in x and z at one grid (perfect test)
the z spring alone leaves chi^2 2694 and the detailed form 1.4e-4. Where the other direction
barely moves the tested modes the information criterion keeps the named spring: the blind
studies' truths at 05b55cb with springs in y and z, of which z alone was named (X-56 seeds 3, 7
and 9, frame seeds 2 and 5), gain 0.1-8.7 in chi^2 from the detailed form, less than the BIC's
2 ln n (13.5 and 12.0).

Masses. A ``lumped_mass`` is screened and named at one grid or spread in equal shares over a
grid and its free neighbours (:mod:`pipeline.diagnose.effects`), so a mass that sits mostly on
one grid of a spread, or unequally on two grids, is named as the spread or point that fits it
least badly: on the frame blind study's mass seed 12 (15.4 and 2.9 mass units at grids 3007 and
3107, at 2.9 % of the total) the spread of 3107 over 3007 and 3207 was named, which puts a third
of the mass on 3207. Once a mass is named it is fitted again with one mass per grid of its
neighbourhood (:func:`pipeline.diagnose.effects.distributed`: the named grid and the free grids
one element layer around it, or the spread's grids) and the shared (r / L)^2, refitted from
each of the named shares and the whole mass on each other grid in turn (:func:`mass_starts`, exact
analyses), the refit of least BIC kept: chi^2 is not convex in the shares, and the start of
least chi^2 need not lead to the least. On tests/pipeline/diagnose/test_detail.py's frame with
0.020 and 0.006 of its mass at 3007 and 3107, the point mass at 3007 leaves chi^2 369 and the
detailed form 0.0014, the two masses within 1 %. On the frame blind study's mass seed 12 (that
truth, 15.4 and 2.9 mass units at 3007 and 3107, named as the spread above) the named shares
start at chi^2 1328 and refit to 1166, the whole mass at 3007 starts at 2613 and refits to 747;
refitted from the start of least chi^2 alone, the workflow would add the 1166 fit.

The detailed joint, spring or mass replaces the named one when it lowers BIC = chi^2 + p ln n
(Schwarz 1978) over the training data: four more parameters (a joint), one or two (a spring) or
one per grid less one (a mass) must gain more than ln n each in chi^2. The verdict is the named
form's; the detail changes what is added to the model (the bulk data written, the gap after, the
next round's model).
"""
from __future__ import annotations

from dataclasses import replace
from itertools import product

import numpy as np
from scipy.optimize import differential_evolution

from pipeline.diagnose.effects import directional, distributed, every_direction
from pipeline.diagnose.evidence import evaluate_modes
from pipeline.diagnose.fit_statistics import chi_square
from pipeline.diagnose.ladder import reduce_joint
from pipeline.diagnose.refit import Refitted, refit
from pipeline.diagnose.screen import LADDER_KINDS, Screened
from structures.common.errors import InputError, SolverError

#: Most neighbours of a named joint refitted from its values (module docstring): a joint has
#: about four variants per RBE2 (the whole joint, each detached side, its mirror pair).
NEIGHBOUR_REFITS = 4
#: Most neighbours compared with a named joint in their detailed forms (module docstring): each
#: costs a search (about 20 s on the frame, 60 s on the X-56 example); in the three frame seeds
#: of the module docstring the truth was the named fit or one of its two best neighbours.
NEIGHBOUR_DETAILED = 2
#: Where a neighbour's refit starts: the named fit's values with the first (a joint's
#: compliance) times each of these, a sixteenth of a decade apart over the quarter decade either
#: side (the ladder's spacing); the one of least chi^2, analysed exactly.
NEIGHBOUR_STARTS = tuple(10.0 ** (np.arange(-4, 5) / 16.0))
#: Half-width of the search in decades of each component's compliance about the named fit's.
SEARCH_DECADES = 1.0
#: Differential evolution's population per parameter and generations: 6 x 10 x 101 = 6,060
#: analyses on the reduced basis (18 s on the frame). On tests/pipeline/diagnose/test_detail.py's
#: anisotropic joint (perfect data) 15 x 30 stopped at chi^2 62 (40 after the refit) where the
#: truth has 0; 15 x 60, 30 x 30 and 10 x 100 reach 0.3, 1.2 and 0.0 (all 0.00 after the refit).
SEARCH_POPSIZE, SEARCH_GENERATIONS = 10, 100
#: Where a named spring's other directions start, times its stiffness (module docstring): none,
#: then an octave apart from an eighth to four times (49 exact analyses per configuration for two
#: other directions). chi^2 is rugged in them (each mode the spring holds crosses others at its
#: own stiffness): on tests/pipeline/diagnose/test_detail.py's frame grounded in x and z at grid
#: 2009 (0.25 and 0.35 k_ref, z named at 0.359) the starts (0, 1/4, 1, 4) lead the refit to
#: chi^2 2583 (x 0.03, y 0.27) of the named 2694; these reach 1.4e-4 (x 0.2500, z 0.3500).
SPRING_STARTS = (0.0, 0.125, 0.25, 0.5, 1.0, 2.0, 4.0)


def _one_site_neighbour(cand, other, near) -> bool:
    """Whether ``other`` is a candidate of ``cand``'s kind at one site (no mirror pair) next to
    it."""
    return (other.kind == cand.kind and other.get("sites") is None
            and near(cand.location, other.location))


def neighbour_refits(problem, effects, named: Refitted, rows, fits, near, *, n_data: int,
                     jacobian_theta) -> list:
    """Refits of a named joint's neighbours that the screening did not pick (module docstring).

    Parameters
    ----------
    problem : pipeline.diagnose.calibrate.Problem
    effects : sequence of (Candidate, values) already in the model.
    named : Refitted, the named fit (nothing is refitted unless its kind is screened on the
        ladder, :data:`pipeline.diagnose.screen.LADDER_KINDS`).
    rows : list of Screened, the round's screening, best first.
    fits : sequence of Refitted, the round's refits (not refitted again).
    near : callable(location_a, location_b) -> bool, True when b is a's neighbour.
    n_data : int, the number of training data (the BIC's n).
    jacobian_theta : (n_data, n_theta) d r / d theta of the calibration.

    Returns
    -------
    list of Refitted, at most :data:`NEIGHBOUR_REFITS`, each started from the best of
    :data:`NEIGHBOUR_STARTS` about the named fit's values (its own screened values where its
    parameters differ).
    """
    cand = named.candidate
    if cand.kind not in LADDER_KINDS:
        return []
    done = {f.candidate.label for f in fits}
    pool = [row for row in rows
            if row.candidate.label not in done and _one_site_neighbour(cand, row.candidate, near)]
    out = []
    for row in pool[:NEIGHBOUR_REFITS]:
        start = named.values if row.candidate.parameters == cand.parameters else row.values
        found = None
        for factor in NEIGHBOUR_STARTS:
            x = np.array(start, float)
            x[0] *= factor
            try:
                evs = problem.evaluate(named.theta, tuple(effects) + ((row.candidate, x),))
            except (InputError, SolverError):
                continue
            chi2 = chi_square(problem.residual(named.theta, evs))
            if found is None or chi2 < found[1]:
                found = (x, chi2)
        if found is None:
            continue
        fit = refit(problem, named.theta, effects, replace(row, values=found[0]), n_data=n_data,
                    jacobian_theta=jacobian_theta, starts=(1.0,))
        if fit is not None:
            out.append(fit)
    return out


def located(problem, effects, named: Refitted, rows, fits, near, *, n_data: int,
            jacobian_theta) -> list:
    """The named fit and the neighbours it is compared with, each with its detailed form
    (module docstring).

    Parameters
    ----------
    problem : pipeline.diagnose.calibrate.Problem
    effects : sequence of (Candidate, values) already in the model.
    named : Refitted, the named fit.
    rows : list of Screened, the round's screening, best first.
    fits : sequence of Refitted, the round's refits.
    near : callable(location_a, location_b) -> bool, True when b is a's neighbour.
    n_data : int, the number of training data (the BIC's n).
    jacobian_theta : (n_data, n_theta) d r / d theta of the calibration.

    Returns
    -------
    list of (Refitted, Refitted or None)
        The named fit first, then at most :data:`NEIGHBOUR_DETAILED` neighbours (the refitted
        joints of one site next to it, fewest chi^2 first), each with its detailed form
        (:func:`detailed`; None when that does not lower its BIC). Only the named fit for a kind
        without a detailed form.
    """
    cand = named.candidate
    pool = []
    if cand.kind == "joint_flexibility" and has_detail(cand):
        pool = [f for f in fits if f is not named and _one_site_neighbour(cand, f.candidate, near)]
        pool += neighbour_refits(problem, effects, named, rows, fits, near, n_data=n_data,
                                 jacobian_theta=jacobian_theta)
        pool = sorted(pool, key=lambda f: f.chi2)[:NEIGHBOUR_DETAILED]
    return [(f, detailed(problem, effects, f, n_data=n_data, jacobian_theta=jacobian_theta))
            for f in [named] + pool]


def has_detail(candidate) -> bool:
    """Whether ``candidate`` has a detailed form: a joint with two parameters, a spring in one
    direction at one grid, or a mass at one site (module docstring)."""
    if candidate.kind == "joint_flexibility":
        return candidate.parameters == ("compliance", "rotation")
    if candidate.kind == "lumped_mass":
        return candidate.parameters == ("mass", "inertia") and candidate.get("sites") is None
    return (candidate.kind == "boundary_stiffness" and len(candidate.parameters) == 1
            and candidate.get("sites") is None)


def form_text(candidate) -> str:
    """How a detailed ``candidate`` differs from its named form, for the notes."""
    if candidate.kind == "boundary_stiffness":
        return f"as {candidate.label}, a spring in every direction its supports leave free"
    if candidate.kind == "lumped_mass":
        return f"as one mass per grid of {candidate.label}"
    return "with one compliance per CBUSH component"


def mass_starts(problem, effects, theta, candidate, values) -> list:
    """The starts of a mass with one share per grid (module docstring): the named distribution
    and the whole mass on each grid in turn, analysed exactly.

    Parameters
    ----------
    problem : pipeline.diagnose.calibrate.Problem
    effects : sequence of (Candidate, values) already in the model.
    theta : (n_theta,) the nominal parameters, held.
    candidate : Candidate, :func:`pipeline.diagnose.effects.distributed`'s.
    values : (n_grids + 1,) its values: the named shares, then the inertia.

    Returns
    -------
    list of (values, chi2): each distinct start that can be analysed, (n_grids + 1,) values
    and their chi^2, least chi^2 first (empty when none can).
    """
    x0 = np.asarray(values, float)
    n = x0.size - 1
    starts = [x0]
    for i in range(n):
        x = np.append(np.eye(n)[i] * min(x0[:n].sum(), candidate.upper[i]), x0[n])
        if not any(np.array_equal(x, s) for s in starts):     # a point mass's own grid: once
            starts.append(x)
    return _analysed(problem, effects, theta, candidate, starts)


def spring_start(problem, effects, theta, candidate, values, named: int) -> tuple:
    """The best start of a spring in every free direction (module docstring).

    Parameters
    ----------
    problem : pipeline.diagnose.calibrate.Problem
    effects : sequence of (Candidate, values) already in the model.
    theta : (n_theta,) the nominal parameters, held.
    candidate : Candidate, :func:`pipeline.diagnose.effects.every_direction`'s.
    values : (n_dir,) its values: the named stiffness in its direction, 0 in the others.
    named : int, the named direction's position in ``values``.

    Returns
    -------
    values : (n_dir,) the start of least chi^2.
    chi2 : float, its chi^2 (inf when no start can be analysed).
    """
    x0 = np.asarray(values, float)
    others = np.delete(np.arange(x0.size), named)
    size = max(x0[named], candidate.reference[named])
    starts = []
    for factors in product(SPRING_STARTS, repeat=others.size):
        x = x0.copy()
        x[others] = np.minimum(np.array(factors) * size, np.asarray(candidate.upper)[others])
        starts.append(x)
    return (_analysed(problem, effects, theta, candidate, starts) or [(starts[0], np.inf)])[0]


def _analysed(problem, effects, theta, candidate, starts) -> list:
    """[(values, chi2)] of the ``starts`` that can be analysed, least exact chi^2 first."""
    out = []
    for x in starts:
        try:
            evs = problem.evaluate(theta, tuple(effects) + ((candidate, x),))
        except (InputError, SolverError):
            continue
        out.append((x, chi_square(problem.residual(theta, evs))))
    return sorted(out, key=lambda pair: pair[1])


def detailed(problem, effects, fit: Refitted, *, n_data: int, jacobian_theta) -> Refitted | None:
    """The named fit in its detailed form when that lowers BIC, else None (module docstring).

    Parameters
    ----------
    problem : pipeline.diagnose.calibrate.Problem
    effects : sequence of (Candidate, values) already in the model.
    fit : Refitted, the named effect's refit.
    n_data : int, the number of training data (the BIC's n).
    jacobian_theta : (n_data, n_theta) d r / d theta of the calibration.

    Returns
    -------
    Refitted or None
    """
    cand = fit.candidate
    if not has_detail(cand):
        return None
    if cand.kind == "boundary_stiffness":
        rich, values = every_direction(problem.model(0, fit.theta, effects), cand, fit.values)
        if len(rich.parameters) == 1:
            return None
        starts = [spring_start(problem, effects, fit.theta, rich, values,
                               rich.parameters.index(cand.parameters[0]))]
    elif cand.kind == "lumped_mass":
        try:
            rich, values = distributed(problem.model(0, fit.theta, effects), cand, fit.values)
        except InputError:
            return None
        starts = mass_starts(problem, effects, fit.theta, rich, values)
    else:
        try:
            rich, values = directional(cand, fit.values)
        except InputError:
            return None
        starts = [search(problem, effects, fit.theta, rich, values)]
    outs = [refit(problem, fit.theta, effects, Screened(rich, x, chi2, fit.chi2 - chi2, None),
                  n_data=n_data, jacobian_theta=jacobian_theta)
            for x, chi2 in starts if np.isfinite(chi2)]
    out = min((o for o in outs if o is not None), key=lambda o: o.bic, default=None)
    return out if out is not None and out.bic < fit.bic else None


def search(problem, effects, theta, candidate, values) -> tuple:
    """The global search of step 1 (module docstring).

    Parameters
    ----------
    problem : pipeline.diagnose.calibrate.Problem
    effects : sequence of (Candidate, values) already in the model.
    theta : (n_theta,) the nominal parameters, held.
    candidate : Candidate, a directional ``joint_flexibility``.
    values : (6,) the compliances the search is centred on (> 0).

    Returns
    -------
    values : (6,) the best compliances found (``values`` when no basis applies).
    chi2 : float, their chi^2 on the reduced bases (inf when no basis applies).
    """
    refs = problem.refs
    bases = []
    for i, ref in enumerate(refs):
        sensors = ref.sensor_index if ref.has_shapes else np.zeros(0, int)
        try:
            basis = reduce_joint(problem.model(i, theta, effects), candidate, sensors, ref.nmodes,
                                 any_size=True)
        except (InputError, SolverError):
            basis = None
        if basis is None:
            return np.asarray(values, float), np.inf
        bases.append(basis)
    prior = problem.prior_residual(theta)

    def chi2(log_c):
        c = 10.0 ** log_c
        parts = []
        for ref, basis in zip(refs, bases):
            try:
                modes, shapes = basis.modes(c)
            except SolverError:
                return np.inf
            parts.append(evaluate_modes(ref, modes["frequency"].values,
                                        shapes if ref.has_shapes else None,
                                        basis.properties(c), modes=modes).vector(ref))
        return chi_square(np.concatenate(parts + [prior]))

    centre = np.log10(np.asarray(values, float))
    top = np.log10(np.asarray(candidate.upper, float))
    bounds = list(zip(centre - SEARCH_DECADES, np.minimum(centre + SEARCH_DECADES, top)))
    best = differential_evolution(chi2, bounds, x0=np.clip(centre, *np.transpose(bounds)),
                                  popsize=SEARCH_POPSIZE, maxiter=SEARCH_GENERATIONS, tol=0.0,
                                  seed=0, polish=False, updating="immediate")
    return 10.0 ** best.x, float(best.fun)
