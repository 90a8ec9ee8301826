"""The diagnose problem (configurations, their models and residuals) and the nominal calibration.

Nominal parameters (DESIGN.md section 5 step 2): Young's modulus of every MAT1 (E and G linked,
so the Poisson ratio stays) and MAT8 (E1, E2, G12 linked) material that an element uses, and one
scale of all CONM2 masses, each a relative change theta (x = x0 (1 + theta)) within
+-``CALIBRATION_BOUND``, shared by the configurations (one structure, several loadings), applied
with :func:`structures.design.apply_design`. They are fitted by bounded least squares
(``scipy.optimize.least_squares``) of the training residual (:mod:`pipeline.diagnose.evidence`)
plus a Gaussian prior on the mass scale, theta_m / sigma_m (:func:`mass_prior_scale`): the CONM2s
scatter independently (``DiagnoseSettings.model_scatter`` each), so the common part of their
errors, all that a uniform scale can represent, is known sqrt(N_eff) times better than each mass. Without it the scale
soaks up a missing mass and the weighing, the evidence that tells a mass from a stiffness error
(issue 14 step 2), is gone after the calibration. The prior is truncated at ``PRIOR_SIGMAS``
sigma_m (the scale's bounds, :attr:`Problem.bounds`): when the modal residual is far above its
scales (a large missing effect, hundreds of times chi^2 / dof) a Gaussian prior row is outweighed
and the scale would still run to +-10 %, which independent scatter of the masses cannot do. A
material's modulus is one value for all its elements (no averaging): it keeps the box bounds
+-``CALIBRATION_BOUND`` only.

Model-form flags (the fit "stalls", DESIGN.md section 5): a parameter within ``BOUND_TOLERANCE``
of its bound (for the mass scale: ``PRIOR_SIGMAS`` prior standard deviations from nominal);
configurations wanting values that differ by more than ``CONSISTENCY_SIGMAS`` times their
uncertainty (one Gauss-Newton step per configuration from the joint solution, with the
joint Jacobian's blocks: theta_c = theta - (J_c^T J_c)^-1 J_c^T r_c, covariance (J_c^T J_c)^-1);
a residual that fails the goodness-of-fit test; frequency residuals whose signs run in long
stretches along the modes (runs test p below ``RUNS_P``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from pipeline.diagnose.evidence import evaluate
from pipeline.diagnose.fit_statistics import chi_square, gof_limit, runs_test
from structures.design import DesignVariable, apply_design, bind, material_ids, write_tuned_bdf
from structures.model import FEModel

#: Bound of every nominal parameter (relative): a material's modulus or the masses are known to
#: about +-10 % before a test; a larger change is a model-form problem, not a calibration.
CALIBRATION_BOUND = 0.10
#: A parameter closer than this (relative, of the bound) to its bound sits on it.
BOUND_TOLERANCE = 0.02
#: Configurations disagree when their estimates differ by more than this many standard deviations.
CONSISTENCY_SIGMAS = 3.0
#: Runs test p-value below which the frequency residual is structured.
RUNS_P = 0.01
#: Truncation of a parameter's Gaussian prior (its bounds): beyond 3 standard deviations
#: (probability 0.27 %) a change is not the nominal scatter.
PRIOR_SIGMAS = 3.0
#: Optimiser scaling of the relative parameters (theta / THETA_SCALE is of order one).
THETA_SCALE = 0.02
#: Relative forward-difference step of the optimiser (of max(1, |theta| / THETA_SCALE); small
#: against the parameters' scale, the pairing held, :func:`forward_columns`).
DIFF_STEP = 1e-4
#: Most residual evaluations of the calibration (a few Gauss-Newton iterations of ~3 parameters).
CALIBRATION_NFEV = 40


def _material_variables(model: FEModel) -> list:
    used = set()
    for es in model.elements.values():
        for pid in np.unique(es.pids):
            prop = model.properties.get(int(pid))
            if prop is None:
                continue
            used |= material_ids(prop)
    out = []
    for mid in sorted(used):
        mat = model.materials.get(mid)
        if mat is None:
            continue
        if mat.card == "MAT1" and mat.fields.get("E"):
            fields = [("MAT1", mid, "E")] + ([("MAT1", mid, "G")] if mat.fields.get("G") else [])
        elif mat.card == "MAT8" and mat.fields.get("E1"):
            fields = [("MAT8", mid, f) for f in ("E1", "E2", "G12") if mat.fields.get(f)]
        else:
            continue
        out.append(DesignVariable(f"E{mid}", tuple(fields)))
    return out


def mass_prior_scale(model: FEModel, scatter: float) -> float:
    """Prior standard deviation sigma_m of the uniform CONM2 mass scale theta_m of a model.

    Every CONM2 mass m_i is off by an independent relative error e_i of standard deviation
    s = ``scatter``. A uniform scale (and the total mass) follows their mass-weighted mean
    theta_m = sum m_i e_i / sum m_i, whose standard deviation is

        sigma_m = s sqrt(sum m_i^2) / sum m_i = s / sqrt(N_eff),  N_eff = (sum m_i)^2 / sum m_i^2

    (the variance of a weighted mean of independent errors; N_eff is Kish's (1965) effective
    number: N equal masses give s / sqrt(N), one mass gives s).

    The residual's covariance (:mod:`pipeline.diagnose.scatter`) already counts the same
    per-mass scatter, its uniform part included, so along the direction of a uniform scale the
    data and this prior both carry it. That uniform part is the share
    1 / N_eff of the mass scatter's variance (0.04 on the frame, N_eff = 23.3): counted twice, a
    uniform mass change is allowed the variance 2 sigma_m^2 instead of sigma_m^2 (sqrt(2) in
    standard deviation), while the per-mass noise that hides single masses is unchanged.

    Parameters
    ----------
    model : FEModel
    scatter : float, s.

    Returns
    -------
    float
        sigma_m; nan without CONM2 mass.
    """
    m = np.asarray(model.masses.mass, float)
    total = float(np.sum(m))
    if total == 0.0:
        return float("nan")
    return float(scatter * np.sqrt(np.sum(m * m)) / total)       # weighted mean of independent e_i


def _mass_variable(model: FEModel) -> list:
    hit = np.flatnonzero(np.asarray(model.masses.mass) != 0.0)
    if hit.size == 0:
        return []
    fields = tuple(("CONM2", int(model.masses.eids[i]), "M") for i in hit)
    return [DesignVariable("mass", fields)]


def write_calibrated_deck(deck_in, deck_out, model: FEModel, nominal):
    """Write ``deck_in`` with the nominal parameters ``nominal`` applied (the model of a gap).

    Parameters
    ----------
    deck_in, deck_out : path-like
        ``model`` is ``read_model(deck_in)``.
    model : FEModel
    nominal : mapping {parameter name: relative change theta}
        :attr:`pipeline.diagnose.DiagnoseResult.calibrated` (the model of ``gap_before``) or
        ``nominal`` (of ``gap_after``); a parameter the model lacks is skipped, one missing from
        the mapping is left at 0.

    Returns
    -------
    Path
        The deck (:func:`structures.design.write_tuned_bdf`: x = x0 (1 + theta) of the same
        design space as :meth:`Problem.model`).
    """
    variables = _material_variables(model) + _mass_variable(model)
    space = bind(variables, [model])
    theta = np.array([float(nominal.get(v.name, 0.0)) for v in variables])
    return write_tuned_bdf(deck_in, deck_out, space, space.x0 * (1.0 + theta))


@dataclass(frozen=True)
class Problem:
    """Configurations with their nominal models, references and nominal parameters.

    Attributes
    ----------
    names : tuple of str, the nominal parameters (``E<mid>``, ``mass``), shared by the
        configurations.
    refs : tuple of Reference, one per configuration.
    models : tuple of FEModel, nominal.
    spaces : tuple of DesignSpace, per configuration (the variables it has).
    index : tuple of int arrays, per configuration the theta index of each variable of its space.
    prior : (n_theta,) standard deviation of every parameter's Gaussian prior (inf: box bounds
        only).
    """

    names: tuple
    refs: tuple
    models: tuple
    spaces: tuple
    index: tuple
    prior: np.ndarray

    @classmethod
    def build(cls, refs, models, scatter: float) -> "Problem":
        """Nominal parameters of every configuration's model (shared by name).

        The mass scale's prior is the largest :func:`mass_prior_scale` of the configurations (the
        one with the fewest effective masses: one shared scale must fit all); with
        ``scatter`` = 0 the masses are exact and the scale is not a parameter.
        """
        names, spaces, index = [], [], []
        sigma_m = max((s for s in (mass_prior_scale(m, scatter) for m in models)
                       if np.isfinite(s)), default=0.0)
        for model in models:
            variables = _material_variables(model) + (_mass_variable(model) if sigma_m > 0
                                                       else [])
            space = bind(variables, [model])
            for var in variables:
                if var.name not in names:
                    names.append(var.name)
            spaces.append(space)
            index.append(np.array([names.index(v.name) for v in variables], int))
        prior = np.array([sigma_m if name == "mass" else np.inf for name in names], float)
        return cls(tuple(names), tuple(refs), tuple(models), tuple(spaces), tuple(index), prior)

    @property
    def n_theta(self) -> int:
        return len(self.names)

    def model(self, i: int, theta, effects=()) -> FEModel:
        """Configuration ``i``'s model at nominal parameters ``theta`` with ``effects`` applied.

        ``effects`` is a sequence of (Candidate, values) applied in order
        (:func:`pipeline.diagnose.apply.apply_effect`).
        """
        from pipeline.diagnose.apply import apply_effect

        space = self.spaces[i]
        model = self.models[i]
        if len(space):
            x = space.x0 * (1.0 + np.asarray(theta, float)[self.index[i]])
            model = apply_design(model, space, x)
        for candidate, values in effects:
            model = apply_effect(model, candidate, np.asarray(values, float))
        return model

    def evaluate(self, theta, effects=(), paired=None) -> list:
        """Evaluations (:class:`Evaluation`) of every configuration; ``paired`` (one (n_test,)
        array per configuration, e.g. :func:`pairings` of other evaluations) keeps a pairing
        instead of pairing the modes again."""
        paired = paired if paired is not None else [None] * len(self.refs)
        return [evaluate(ref, self.model(i, theta, effects), paired=p)
                for i, (ref, p) in enumerate(zip(self.refs, paired))]

    def vector(self, evaluations) -> np.ndarray:
        """Training residual vector of the data over the configurations."""
        return np.concatenate([ev.vector(ref) for ev, ref in zip(evaluations, self.refs)])

    @property
    def bounds(self) -> np.ndarray:
        """(n_theta,) bound b of every parameter, -b <= theta <= b: ``CALIBRATION_BOUND``, or
        ``PRIOR_SIGMAS`` prior standard deviations when that is tighter."""
        return np.minimum(CALIBRATION_BOUND, PRIOR_SIGMAS * self.prior)

    def prior_residual(self, theta) -> np.ndarray:
        """theta_i / sigma_i of every parameter with a finite prior, shape (n_prior,)."""
        finite = np.isfinite(self.prior)
        return np.asarray(theta, float)[finite] / self.prior[finite]

    def modal_rows(self) -> np.ndarray:
        """(n_data,) bool: the entries of :meth:`residual` that are modal (the training modes'
        frequencies and shapes, whose scales assume a model scatter and noise level), in its
        order; the others (each configuration's weighing, :mod:`pipeline.diagnose.weighing`,
        and :meth:`prior_residual`) have stated scales
        (:func:`pipeline.diagnose.verdict.round_scores`)."""
        parts = []
        for ref in self.refs:
            n_shape = int(ref.shape_keep[0].sum()) if ref.has_shapes else 0
            parts += [np.ones(int(ref.train.sum()) * (1 + n_shape), bool),
                      np.zeros(len(ref.mass_scale), bool)]
        return np.concatenate(parts + [np.zeros(int(np.isfinite(self.prior).sum()), bool)])

    def residual(self, theta, evaluations) -> np.ndarray:
        """Training residual: the data (:meth:`vector`) then the prior (:meth:`prior_residual`)
        at the nominal parameters ``theta`` of ``evaluations``."""
        return np.concatenate([self.vector(evaluations), self.prior_residual(theta)])


@dataclass(frozen=True)
class Calibration:
    """Result of :func:`calibrate`.

    Attributes
    ----------
    theta : (n_theta,) relative changes of the nominal parameters.
    chi2 : float, training chi^2 at theta.
    n_data : int, training residuals (the prior's included).
    evaluations : list of Evaluation at theta.
    flags : tuple of str, model-form warnings (empty when the fit is clean).
    per_configuration : {configuration: (n_theta,) estimates} from one Gauss-Newton step each.
    jacobian : (n_data, n_theta) d r / d theta at the solution, prior rows included, the pairing
        held (:func:`forward_columns`; reused by the refits).
    """

    theta: np.ndarray
    chi2: float
    n_data: int
    evaluations: list
    flags: tuple
    per_configuration: dict
    jacobian: np.ndarray


def pairings(evaluations) -> list:
    """The pairing of every configuration's evaluation, for :meth:`Problem.evaluate`."""
    return [ev.paired for ev in evaluations]


def memoised(residual, known=None) -> tuple:
    """``fun(z)`` -> r and ``at(z)`` -> (r, pairing) over one cache of ``residual(z)`` -> (r,
    pairing) (``known``: {z.tobytes(): (r, pairing)} already evaluated): the optimiser asks for
    the residual and then the Jacobian at the same point, whose columns hold its pairing."""
    cache = dict(known or {})

    def at(z):
        key = z.tobytes()
        if key not in cache:
            cache[key] = residual(z)
        return cache[key]

    return (lambda z: at(z)[0]), at


def forward_columns(residual, z, steps, upper, r) -> list:
    """Forward-difference columns d residual / d z_k of the first ``len(steps)`` entries of
    ``z``, each stepped by ``steps[k]`` toward the inside of ``upper``; ``r`` is residual(z).

    ``residual`` must keep the pairing of z's modes (:meth:`Problem.evaluate` with ``paired``):
    a test mode whose pairing cost ties between two analysis modes re-pairs under a step of any
    size, and the jump between their residuals (on the frame blind study's taper seed 6, test
    mode 20 between analysis modes at 19.80 and 21.28 Hz: 6.7 sigma in its frequency entry at a
    step of 1e-4 in the mass scale) would enter the derivative divided by the step: a column
    ~10^4 times too long, which freezes that parameter in every fit that reuses it.
    """
    cols = []
    for k, h in enumerate(steps):
        h = h if z[k] + h <= upper[k] else -h
        step = np.array(z, float)
        step[k] += h
        cols.append((residual(step) - r) / h)
    return cols


def calibrate(problem: Problem, effects=()) -> Calibration:
    """Fit the nominal parameters within their bounds (:attr:`Problem.bounds`) and their prior
    (:meth:`Problem.residual`); flag model-form error."""
    n = problem.n_theta
    if n == 0:
        evs = problem.evaluate(np.zeros(0), effects)
        r = problem.residual(np.zeros(0), evs)
        return Calibration(np.zeros(0), chi_square(r), r.size, evs, (), {}, np.zeros((r.size, 0)))
    bound = problem.bounds / THETA_SCALE

    def residual(z, paired=None):
        theta = z * THETA_SCALE
        evs = problem.evaluate(theta, effects, paired)
        return problem.residual(theta, evs), pairings(evs)

    fun, at = memoised(residual)

    def jac(z):
        r, paired = at(z)
        return np.column_stack(forward_columns(lambda y: residual(y, paired)[0], z,
                                               DIFF_STEP * np.maximum(1.0, np.abs(z)), bound, r))

    sol = least_squares(fun, np.zeros(n), jac=jac, bounds=(-bound, bound), method="trf",
                        max_nfev=CALIBRATION_NFEV)
    theta = sol.x * THETA_SCALE
    evs = problem.evaluate(theta, effects)
    r = problem.residual(theta, evs)
    chi2 = chi_square(r)
    flags = []
    for name, t, b, sd in zip(problem.names, theta, problem.bounds, problem.prior):
        if abs(abs(t) - b) >= BOUND_TOLERANCE * b:
            continue
        if np.isfinite(sd):
            flags.append(f"nominal parameter {name} sits on its bound ({100 * t:+.2f} %, "
                         f"{PRIOR_SIGMAS:g} times its prior standard deviation {100 * sd:.2f} % "
                         "from independent scatter of the masses): a missing or misplaced mass, "
                         "or a model-form error the scale compensates for.")
        else:
            flags.append(f"nominal parameter {name} sits on its bound ({100 * t:+.1f} %): the "
                         "calibration compensates for something it cannot represent.")
    jac = sol.jac / THETA_SCALE
    per_conf = _per_configuration(problem, evs, jac, theta, flags)
    dof = r.size - n
    if chi2 > gof_limit(dof):
        flags.append(f"after calibration chi^2 / dof = {chi2 / max(dof, 1):.2f} fails the "
                     f"goodness-of-fit test (limit {gof_limit(dof) / max(dof, 1):.2f}).")
    for ev, ref in zip(evs, problem.refs):
        p = runs_test(ev.frequency[ref.train])                   # held-out modes judge the gap only
        if p < RUNS_P:
            flags.append(f"configuration {ref.name}: the frequency errors run in long stretches "
                         f"of one sign along the training modes (runs test p = {p:.1e}): a "
                         "structured residual.")
    return Calibration(theta, chi2, r.size, evs, tuple(flags), per_conf, jac)


def _per_configuration(problem: Problem, evs, jac, theta, flags: list) -> dict:
    """One Gauss-Newton step per configuration from the joint solution; flags disagreements."""
    out, covs = {}, {}
    start = 0
    for ev, ref in zip(evs, problem.refs):
        r_c = ev.vector(ref)
        j_c = jac[start:start + r_c.size]
        start += r_c.size
        jtj = j_c.T @ j_c
        seen = np.diag(jtj) > 0
        est = np.full(theta.size, np.nan)
        cov = np.full(theta.size, np.inf)
        if seen.any():
            sub = jtj[np.ix_(seen, seen)]
            inv = np.linalg.pinv(sub)
            est[seen] = theta[seen] - inv @ (j_c[:, seen].T @ r_c)
            cov[seen] = np.diag(inv)
        out[ref.name] = est
        covs[ref.name] = cov
    names = list(out)
    for a in range(len(names)):
        for b in range(a + 1, len(names)):
            diff = out[names[a]] - out[names[b]]
            sd = np.sqrt(covs[names[a]] + covs[names[b]])
            bad = np.isfinite(diff) & (np.abs(diff) > CONSISTENCY_SIGMAS * sd)
            for k in np.flatnonzero(bad):
                flags.append(f"configurations {names[a]} and {names[b]} want {problem.names[k]} "
                             f"{100 * out[names[a]][k]:+.1f} % and {100 * out[names[b]][k]:+.1f} % "
                             f"(difference {abs(diff[k]) / sd[k]:.1f} sigma): inconsistent.")
    return out

