"""Model tuning: the optimisation problem of the paper's eq. 25 over several configurations.

    minimise  J = sum_i w_i J_i          (indices selected as objective terms)
    such that J_k <= eps_k               (indices selected as constraints; MAC: J_k >= eps_k)

over design variables shared by every configuration (e.g. empty and full fuel decks with the same
structural properties, each with its own GVT). Every evaluation pairs test and analysis modes anew by
the assignment on |cross-orthogonality| (mode tracking through interchange, paper sec. V.A) before the
indices (:mod:`structures.indices`) are formed; gradients come from :mod:`structures.sensitivity`.

Optimisers: scipy SLSQP and trust-constr with analytic gradients, and differential evolution (global,
gradient-free, for hard starts) followed by an SLSQP polish. The optimiser works on the scaled
variables z = x / scale with the side constraints as bounds; constraints are passed normalised,
1 - J_k / eps_k >= 0. Every evaluation is recorded: the history Dataset has dims ``iteration``
(evaluation number), ``design_variable`` and ``index``.

Besides the paper's indices of every configuration, each design variable v has a design-change index
``design:change:v`` = ((x_v - x0_v) / x0_v)^2 (:func:`design_change`): selected as objective terms
(e.g. ``("design:change:*", lam)``) they regularise the update for noisy test data.

Cost: the optimisers ask for function values at line-search points and for gradients only at
accepted iterates; gradients are computed only when asked for, and a gradient at the design of the
last function value reuses its eigen solve. The configurations are independent, so they are
evaluated on concurrent threads (SuperLU, ARPACK and the large numpy kernels release the GIL), each
with one BLAS thread: the small dense products of a 30-mode problem gain nothing from BLAS threads,
and threads spinning on cores shared with other work slowed an evaluation several times.

Memory (n a-set DOFs, m modes, v design variables, r measured DOFs, per configuration): held for
the evaluator's life, the sub-assembly (:mod:`structures.subassembly`: the start K and M, each
polynomial group's coefficients, terms x group non-zeros, and its reduction operator over the
raw element entries) and the last design's eigen solve: K, M, the modes (8 n m bytes) and the
factor of K - sigma M (12 nnz(L + U) bytes, the modal method reuses it); ~125 MB in all at
n = 19,872. Held during a gradient: dK_i, dM_i of every variable (the non-zeros of the groups each
touches), the rows-only shape derivatives (8 v r m bytes: the indices need the shapes at the
measured DOFs only) and, modal method, Z1 = S rows^T and Z2 = S M Z1 (2 x 8 n r bytes, 38 MB at
r = 120) or, Nelson's method, one factor of K - lambda_j M at a time with its n x v right-hand
sides; ~100 MB at n = 19,872. The sub-assembly set-up holds a group's samples while it fits them
(samples x non-zero raw entries x 8 bytes: ~210 MB at the peak for the benchmark's skin). The ``workers``
threads run configurations side by side, so their transients add up; configuration i always runs
on thread i % workers, because scipy's SuperLU frees a factor only on the thread that made it
(:func:`_release`). Benchmark (benchmarks/tuning.py, n = 19,872, 2 configurations, m = 30,
v = 24): peak resident memory of a tuning ~0.65 GB (modal) and ~0.77 GB (Nelson).

Restart (the paper's "previous optimization history" start, sec. V.C): :func:`best_from_history`
picks the evaluation with the lowest objective among those whose largest normalised constraint
violation max_k (J_k / eps_k - 1) does not exceed ``allowed_violation`` (default 0.05, i.e. a
constraint may be exceeded by 5 % of its limit); if none qualifies, the least-violating one.
"""
from __future__ import annotations

import ctypes
import ctypes.util
import fnmatch
import os
import time
import weakref
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Callable, Mapping

import numpy as np
import scipy.optimize as so
import xarray as xr
from threadpoolctl import threadpool_limits

from structures.design import DesignSpace, bind
from structures.common.errors import InputError, SolverError
from structures.gvt import check_dofs_in_model, validate_gvt
from structures.indices import build_catalogue, correlation_terms, index_values, mass_quantities
from structures.model import FEModel
from structures.sensitivity import (SHAPE_METHODS, SubAssembly, eigenvalue_derivatives,
                                    mode_shape_derivatives, model_modes)

METHODS = ("slsqp", "trust-constr", "differential_evolution")
FEASIBILITY_TOL = 1e-6


@dataclass(frozen=True)
class TuningConfiguration:
    """One configuration: its model, its GVT and its measured mass properties.

    Attributes
    ----------
    name : str
    model : FEModel (start design)
    gvt : xarray.Dataset (structures.gvt layout)
    nmodes : int, analysis modes (SEREP basis, rigid modes included, as the paper's 30)
    mass : {'deck', 'consistent', 'lumped'}
    test_modes : tuple of int, optional, GVT modes to tune (default all)
    mass_targets : {quantity: value} measured weight, CG, inertias (structures.indices.MASS_QUANTITIES)
    mass_references : {quantity: denominator} for zero targets
    """

    name: str
    model: FEModel
    gvt: xr.Dataset
    nmodes: int = 30
    mass: str = "deck"
    test_modes: tuple | None = None
    mass_targets: Mapping = field(default_factory=dict)
    mass_references: Mapping = field(default_factory=dict)

    def __post_init__(self):
        validate_gvt(self.gvt)
        if self.nmodes < 1:
            raise InputError(f"configuration {self.name}: nmodes = {self.nmodes} must be >= 1.")
        if self.test_modes is not None:
            missing = sorted(set(self.test_modes) - set(self.gvt["mode"].values.tolist()))
            if missing:
                raise InputError(f"configuration {self.name}: test modes {missing} are not in the GVT "
                                 f"{self.gvt['mode'].values.tolist()}.")


@dataclass(frozen=True)
class TuningProblem:
    """Configurations, shared design variables, objective terms and constraints (eq. 25).

    ``objective`` is a tuple of (index name or glob pattern, weight); ``constraints`` a tuple of
    (index name or pattern, eps). Names follow :mod:`structures.indices` (``CONFIG:KIND:MODES``).
    """

    configurations: tuple
    variables: tuple
    objective: tuple
    constraints: tuple = ()
    shape_method: str = "nelson"

    def __post_init__(self):
        if not self.configurations:
            raise InputError("tuning: no configurations.")
        if not self.objective:
            raise InputError("tuning: no objective terms. Fix: select at least one index with a weight.")
        if self.shape_method not in SHAPE_METHODS:
            raise InputError(f"tuning: shape_method {self.shape_method!r}; valid: {list(SHAPE_METHODS)}.")


class _Configuration:
    """Evaluation of one configuration's indices at a design."""

    def __init__(self, cfg: TuningConfiguration, space: DesignSpace, method: str):
        self.cfg, self.space, self.method = cfg, space, method
        gvt = cfg.gvt if cfg.test_modes is None else cfg.gvt.sel(mode=list(cfg.test_modes))
        check_dofs_in_model(gvt, cfg.model.grids.ids)
        if cfg.nmodes > gvt.sizes["dof"]:
            raise InputError(f"configuration {cfg.name}: nmodes = {cfg.nmodes} SEREP modes but only "
                             f"{gvt.sizes['dof']} measured DOFs (SEREP needs n_MD >= m). Fix: lower nmodes.")
        self.catalogue = build_catalogue(cfg.name, gvt["mode"].values, cfg.mass_targets,
                                         cfg.mass_references)
        self.phi_gm = gvt["shape"].values.T
        self.f_test = gvt["frequency"].values
        self.sub = SubAssembly(cfg.model, space, cfg.mass)
        rows = (cfg.model.grids.index(gvt["grid"].values, card="GVT") * 6
                + gvt["component"].values.astype(int) - 1)
        self.rows = self.sub.tr[rows]
        self._last = None

    def _modes(self, x):
        """Eigenpairs at x, reused when the optimiser asks for the gradient at the same design."""
        key = np.asarray(x, float).tobytes()
        if self._last is None or self._last[0] != key:
            self._last = None        # the previous design's K, M and factor go before the new ones
            self._last = (key, model_modes(self.sub, x, self.cfg.nmodes))
        return self._last[1]

    def release(self):
        """Drop the kept eigen solve (K, M, modes and the factor of K - sigma M)."""
        self._last = None

    def evaluate(self, x, gradient: bool):
        k, m, m0, lam, phi, n_rigid, lu = self._modes(x)
        phi_m = self.rows @ phi
        if not gradient:
            mass_v, _ = mass_quantities(m0, self.cfg.model.wtmass)
            terms = correlation_terms(phi_m, self.phi_gm, lam, self.f_test, n_rigid=n_rigid)
            values, _ = index_values(self.catalogue, mass_v, terms)
            return values, None, terms
        dk, dm, dm0 = self.sub.derivatives(x)
        dlam = eigenvalue_derivatives(lam, phi, dk, dm)
        dphi_m = mode_shape_derivatives(k, m, lam, phi, dk, dm, dlam, n_rigid=n_rigid,
                                        rigid=self.sub.rigid, method=self.method, rows=self.rows, lu=lu,
                                        filename=self.cfg.model.filename)
        mass_v, mass_g = mass_quantities(m0, self.cfg.model.wtmass, dm0)
        terms = correlation_terms(phi_m, self.phi_gm, lam, self.f_test, n_rigid=n_rigid,
                                  dphi_m=dphi_m, dlam=dlam)
        values, grad = index_values(self.catalogue, mass_v, terms, mass_g)
        return values, grad, terms


def _libc_trim():
    """glibc's malloc_trim, or None on other C libraries."""
    try:
        return ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6").malloc_trim
    except (OSError, AttributeError):
        return None


_MALLOC_TRIM = _libc_trim()


def _trim_heap():
    """Give the memory freed by the worker threads back to the system (glibc: malloc_trim).

    Each thread allocates its tens-of-MB temporaries in its own malloc arena, which glibc does not
    shrink by itself: without this the resident memory of the 20,000-DOF benchmark grew by about
    50 MB per gradient evaluation (0.7 -> 1.3 GB in 8), with it it stays at 0.5-0.8 GB.
    """
    if _MALLOC_TRIM is not None:
        _MALLOC_TRIM(0)


def _release(pools, configs):
    """Free every configuration's kept factorisation on the thread that made it, then the threads.

    scipy's SuperLU frees its factor only on the thread that allocated it (its allocations are
    registered per thread): a factor dropped on another thread stays allocated for good, and did
    so once per design (+50 MB each at 20,000 DOF) while the configurations moved between the
    threads of a shared pool.
    """
    for i, c in enumerate(configs):
        pools[i % len(pools)].submit(c.release).result()
    for pool in pools:
        pool.shutdown(wait=False)


def _select(patterns, names, what: str):
    """Indices of ``names`` matched by each (pattern, number) pair; InputError if none."""
    out = []
    for pattern, number in patterns:
        hits = [i for i, n in enumerate(names) if fnmatch.fnmatchcase(n, str(pattern))]
        if not hits:
            raise InputError(f"tuning {what}: {pattern!r} names no index. An index names a configuration, "
                             "a kind and tuned (paired) test modes, e.g. 'empty:frequency:7' or "
                             f"'empty:cross_orthogonality:7-9'. Available (first 12): {list(names[:12])}.")
        out += [(i, float(number)) for i in hits]
    return out


def design_change(x, x0):
    """Design-change indices ((x_v - x0_v) / x0_v)^2 and their gradient (diagonal).

    As objective terms with weight lambda they are a Tikhonov regularisation of the update, i.e.
    the log-prior of a Gaussian on the relative parameter changes (maximum a posteriori estimation):
    with the frequency terms weighted 1 (sigma_f), a prior standard deviation sigma_p gives
    lambda = (sigma_f / sigma_p)^2 (Friswell & Mottershead, Finite Element Model Updating in
    Structural Dynamics, 1995, sec. 7.5). Parameters the test data cannot see then stay near their
    start instead of drifting to a bound while the optimiser fits noise.

    Parameters
    ----------
    x, x0 : (nvar,) design and start design

    Returns
    -------
    values : (nvar,); gradient : (nvar, nvar)
    """
    rel = (np.asarray(x, float) - x0) / x0
    return rel ** 2, np.diag(2.0 * rel / x0)


class Evaluator:
    """All configurations of a problem: index values, objective, constraints, history.

    Everything is validated at construction (design variables, index names), before any solve.
    ``workers`` threads evaluate the configurations concurrently (default: one per configuration,
    at most the number of cores), configuration i always on thread i % workers (module docstring,
    memory); the results do not depend on it.
    """

    def __init__(self, problem: TuningProblem, workers: int | None = None):
        self.problem = problem
        self.workers = max(1, min(len(problem.configurations),
                                  workers if workers is not None else os.cpu_count() or 1))
        self.space = bind(problem.variables, [c.model for c in problem.configurations])
        self.configs = [_Configuration(c, self.space, problem.shape_method)
                        for c in problem.configurations]
        _trim_heap()      # the sub-assembly fits' samples (module docstring, memory)
        if any(c.name == "design" for c in problem.configurations):
            raise InputError("tuning: a configuration is named 'design', the prefix of the design-change "
                             "indices. Fix: rename the configuration.")
        nvar = len(problem.variables)
        self.names = ([n for c in self.configs for n in c.catalogue.names]
                      + [f"design:change:{v.name}" for v in problem.variables])
        self.lower_is_better = np.concatenate([c.catalogue.lower_is_better for c in self.configs]
                                              + [np.ones(nvar, bool)])
        self.paper_k = np.concatenate([c.catalogue.paper_k for c in self.configs]
                                      + [np.zeros(nvar, int)])
        obj = _select(problem.objective, self.names, "objective")
        con = _select(problem.constraints, self.names, "constraint")
        self.weights = np.zeros(len(self.names))
        for i, w in obj:
            self.weights[i] = w * (1.0 if self.lower_is_better[i] else -1.0)
        self.limits = np.full(len(self.names), np.nan)
        for i, eps in con:
            if not eps > 0:
                raise InputError(f"tuning constraint {self.names[i]}: limit {eps} must be > 0.")
            self.limits[i] = eps
        self.con_index = np.flatnonzero(np.isfinite(self.limits))
        self.pair_labels = [f"{c.cfg.name}:{t}" for c in self.configs for t in c.catalogue.test_modes]
        self.pair_test_frequency = np.concatenate([c.f_test for c in self.configs])
        self.records = []
        self._cache = {}
        self._pools = None  # worker threads, one executor each, kept for the evaluator's life
        self.counts = {"designs": 0, "gradients": 0}   # evaluations actually computed

    # ------------------------------------------------------------------------------ evaluation
    def evaluate(self, x, gradient: bool = False):
        """(values (nidx,), grad (nidx, nvar) or None) at design x; every new design is recorded."""
        x = self.space.check(np.clip(x, self.space.lower, self.space.upper))
        key = x.tobytes()
        hit = self._cache.get(key)
        if hit is not None and (hit[1] is not None or not gradient):
            return hit[0], hit[1]
        self.counts["designs"] += hit is None                 # a new design: one eigen solve each
        self.counts["gradients"] += bool(gradient)
        vals, grads, pairs, inter, freqs = [], [], [], [], []
        # one BLAS thread per configuration, the configurations side by side (module docstring)
        with threadpool_limits(limits=1, user_api="blas"):
            if self.workers > 1:
                # configuration i always on thread i % workers (SuperLU factors: see _release)
                if self._pools is None:
                    self._pools = [ThreadPoolExecutor(1, thread_name_prefix=f"tuning{i}")
                                   for i in range(self.workers)]
                    weakref.finalize(self, _release, self._pools, self.configs).atexit = False
                futures = [self._pools[i % self.workers].submit(c.evaluate, x, gradient)
                           for i, c in enumerate(self.configs)]
                results = [f.result() for f in futures]
                _trim_heap()
            else:
                results = [c.evaluate(x, gradient) for c in self.configs]
        for v, g, terms in results:
            vals.append(v)
            grads.append(g)
            pairs.append(terms.fe_index + 1)
            inter.append(terms.interchanged)
            freqs.append(terms.fe_frequency)
        change, d_change = design_change(x, self.space.x0)
        values = np.concatenate(vals + [change])
        grad = np.concatenate(grads + [d_change]) if gradient else None
        self._cache = {key: (values, grad)}
        if hit is None:
            self.records.append((x.copy(), values, np.concatenate(pairs), np.concatenate(inter),
                                 np.concatenate(freqs)))
        return values, grad

    def objective(self, values) -> float:
        return float(np.nansum(self.weights * values))                     # eq. 25 objective

    def normalised_constraints(self, values) -> np.ndarray:
        """1 - J_k / eps_k (upper) or J_k / eps_k - 1 (MAC); >= 0 when satisfied."""
        ratio = values[self.con_index] / self.limits[self.con_index]
        return np.where(self.lower_is_better[self.con_index], 1.0 - ratio, ratio - 1.0)

    def max_violation(self, values) -> float:
        g = self.normalised_constraints(values)
        return float(max(0.0, -g.min())) if g.size else 0.0

    # ------------------------------------------------------------------------- scipy callables
    def f(self, z):
        return self.objective(self.evaluate(self.space.from_scaled(z))[0])

    def df(self, z):
        _, g = self.evaluate(self.space.from_scaled(z), True)
        return (self.weights[:, None] * g).sum(axis=0) * self.space.scale

    def g(self, z):
        return self.normalised_constraints(self.evaluate(self.space.from_scaled(z))[0])

    def dg(self, z):
        _, grad = self.evaluate(self.space.from_scaled(z), True)
        idx = self.con_index
        sign = np.where(self.lower_is_better[idx], -1.0, 1.0)
        return (sign / self.limits[idx])[:, None] * grad[idx] * self.space.scale[None, :]

    # --------------------------------------------------------------------------------- history
    def history(self) -> xr.Dataset:
        """Every evaluation: design, every index, objective, violation, feasibility, pairing."""
        if not self.records:
            raise SolverError("tuning: no evaluation was recorded.")
        x, v, p, inter, f = (np.array(a) for a in zip(*self.records))
        obj = np.array([self.objective(r) for r in v])
        viol = np.array([self.max_violation(r) for r in v])
        role = np.where(self.weights != 0, "objective",
                        np.where(np.isfinite(self.limits), "constraint", "monitor"))
        it, dv, ix, pr = ("iteration",), ("iteration", "design_variable"), ("iteration", "index"), \
            ("iteration", "pair")
        return xr.Dataset(
            {"design": (dv, x, {"long_name": "design variable values (unscaled)"}),
             "index_value": (ix, v, {"long_name": "performance index J_k (paper eqs. 1-24)"}),
             "objective": (it, obj, {"long_name": "sum_i w_i J_i (eq. 25)"}),
             "max_violation": (it, viol, {"long_name": "max_k (J_k/eps_k - 1), 0 if feasible"}),
             "feasible": (it, viol <= FEASIBILITY_TOL),
             "paired_fe_mode": (pr, p, {"long_name": "analysis mode paired with the test mode"}),
             "paired_fe_frequency": (pr, f, {"units": "Hz"}),
             "interchanged": (pr, inter)},
            coords={"iteration": np.arange(len(x)), "design_variable": self.space.names,
                    "index": self.names, "pair": self.pair_labels,
                    "test_frequency": ("pair", self.pair_test_frequency, {"units": "Hz"}),
                    "lower": ("design_variable", self.space.lower),
                    "upper": ("design_variable", self.space.upper),
                    "start": ("design_variable", self.space.x0),
                    "weight": ("index", self.weights), "limit": ("index", self.limits),
                    "role": ("index", role.astype(str)), "paper_k": ("index", self.paper_k)},
            attrs={"reference": "Pak & Truong, X-56A model tuning, eqs. 1-25",
                   "constraint_form": "J_k <= eps_k (MAC: J_k >= eps_k)",
                   "mac_objective_sign": "MAC terms enter the objective with a minus sign"})


@dataclass(frozen=True)
class TuningResult:
    """Outcome of :func:`tune`: the design, the history and the optimiser's own report."""

    x: np.ndarray
    space: DesignSpace
    history: xr.Dataset
    success: bool
    message: str
    iterations: int


def best_iteration(history: xr.Dataset, allowed_violation: float = 0.05) -> int:
    """The evaluation the restart rule picks (module docstring): lowest objective with max
    violation <= ``allowed_violation``, else the least violating one."""
    viol, obj = history["max_violation"].values, history["objective"].values
    ok = np.flatnonzero(viol <= allowed_violation)
    return int(ok[np.argmin(obj[ok])] if ok.size else np.argmin(viol))


def best_from_history(history: xr.Dataset, allowed_violation: float = 0.05) -> np.ndarray:
    """The restart design: that of :func:`best_iteration`.

    Returns
    -------
    (nvar,) design values
    """
    return history["design"].values[best_iteration(history, allowed_violation)].copy()


def tune(problem: TuningProblem, *, method: str = "slsqp", start=None, maxiter: int = 50,
         tol: float = 1e-8, progress: Callable | None = None, seed: int = 0, popsize: int = 8,
         evaluator: Evaluator | None = None) -> TuningResult:
    """Solve the tuning problem (eq. 25).

    Parameters
    ----------
    problem : TuningProblem
    method : {'slsqp', 'trust-constr', 'differential_evolution'}
    start : (nvar,) design values, default the decks' values (e.g. :func:`best_from_history`)
    maxiter : int, optimiser iterations (generations for differential evolution)
    tol : float
    progress : callable(iteration, objective, max_violation, seconds), called once per iteration
    seed, popsize : int, for differential evolution (population popsize x nvar per generation)

    Returns
    -------
    TuningResult
    """
    if method not in METHODS:
        raise InputError(f"tuning: unknown method {method!r}; valid: {list(METHODS)}.")
    ev = evaluator or Evaluator(problem)
    space = ev.space
    x_start = space.x0 if start is None else space.check(start)
    z0 = space.to_scaled(x_start)
    bounds = so.Bounds(space.to_scaled(space.lower), space.to_scaled(space.upper))
    t0, count = time.perf_counter(), [0]

    def callback(*args):
        count[0] += 1
        if progress is not None:
            z = args[0] if not isinstance(args[0], so.OptimizeResult) else args[0].x
            values, _ = ev.evaluate(space.from_scaled(np.asarray(z)))
            progress(count[0], ev.objective(values), ev.max_violation(values),
                     time.perf_counter() - t0)

    ev.evaluate(x_start)
    has_con = ev.con_index.size > 0
    if method == "slsqp":
        cons = [{"type": "ineq", "fun": ev.g, "jac": ev.dg}] if has_con else []
        res = so.minimize(ev.f, z0, jac=ev.df, method="SLSQP", bounds=bounds, constraints=cons,
                          tol=tol, callback=callback, options={"maxiter": maxiter})
    elif method == "trust-constr":
        cons = [so.NonlinearConstraint(ev.g, 0.0, np.inf, jac=ev.dg)] if has_con else []
        res = so.minimize(ev.f, z0, jac=ev.df, method="trust-constr", bounds=bounds,
                          constraints=cons, callback=callback,
                          options={"maxiter": maxiter, "gtol": tol, "xtol": tol})
    else:
        cons = [so.NonlinearConstraint(ev.g, 0.0, np.inf)] if has_con else ()
        glob = so.differential_evolution(ev.f, bounds, constraints=cons, maxiter=maxiter, seed=seed,
                                         popsize=popsize, polish=False, x0=z0, callback=callback,
                                         tol=tol)
        cons = [{"type": "ineq", "fun": ev.g, "jac": ev.dg}] if has_con else []
        res = so.minimize(ev.f, glob.x, jac=ev.df, method="SLSQP", bounds=bounds, constraints=cons,
                          tol=tol, callback=callback, options={"maxiter": maxiter})
    x = space.check(np.clip(space.from_scaled(res.x), space.lower, space.upper))
    ev.evaluate(x)
    return TuningResult(x=x, space=space, history=ev.history(), success=bool(res.success),
                        message=str(res.message), iterations=count[0])
