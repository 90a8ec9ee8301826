"""The named effect in more detail: a joint's six CBUSH components fitted one by one.

The screening and the naming use a joint's two parameters (compliance and rotation,
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
2. *Refit.* The bounded least squares of :func:`pipeline.diagnose.screen.refit` (exact
   reanalysis, the nominal parameters free) from the search's best point.

The data need not prefer the truth's valley: on the frame's joint seed 3 the search ends at
chi^2 484 (named 616), the truth's compliances give 548 and a refit from them 495; the held-out
frequency error falls from 19.0 to 6.2 % but the largest cross-orthogonality off-diagonal rises
from 0.81 to 0.91.

The six-component joint replaces the named one when it lowers BIC = chi^2 + p ln n (Schwarz
1978) over the training data: four more parameters must gain more than 4 ln n in chi^2. The
verdict is the two-parameter fit's; the detail changes what is added to the model (the bulk data
written, the gap after, the next round's model).
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import differential_evolution

from pipeline.diagnose.effects import directional
from pipeline.diagnose.evidence import chi_square, evaluate_modes
from pipeline.diagnose.ladder import reduce_joint
from pipeline.diagnose.screen import Refitted, Screened, refit
from structures.common.errors import InputError, SolverError

#: Kinds that have a detailed form.
DETAILED_KINDS = ("joint_flexibility",)
#: Half-width of the search in decades of each component's compliance about the named fit's.
SEARCH_DECADES = 1.0
#: Differential evolution's population per parameter and generations: 6 x 10 x 101 = 6,060
#: analyses on the reduced basis (18 s on the frame). On tests/pipeline/diagnose/test_detail.py's
#: anisotropic joint (perfect data) 15 x 30 stopped at chi^2 62 (40 after the refit) where the
#: truth has 0; 15 x 60, 30 x 30 and 10 x 100 reach 0.3, 1.2 and 0.0 (all 0.00 after the refit).
SEARCH_POPSIZE, SEARCH_GENERATIONS = 10, 100


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
    if cand.kind not in DETAILED_KINDS or cand.parameters != ("compliance", "rotation"):
        return None
    try:
        rich, values = directional(cand, fit.values)
    except InputError:
        return None
    start, chi2 = search(problem, effects, fit.theta, rich, values)
    out = refit(problem, fit.theta, effects, Screened(rich, start, chi2, fit.chi2 - chi2, None),
                n_data=n_data, jacobian_theta=jacobian_theta)
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
