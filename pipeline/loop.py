"""The tuning stage of the loop: its problem from a mode selection, and the rule that stops the loop.

Objective and constraints of stage n (paper eq. 25, sec. V; index names of structures.indices,
``C:kind:modes`` with GVT test-mode numbers). A test mode is *primary* (or secondary) when the FE
mode paired with it in the previous stage's correlation is a primary (secondary) mode of that
stage's selection (pipeline.selection). For every configuration C:

- objective, weight 1 each: ``C:frequency:t`` of every primary test mode t and
  ``C:cross_orthogonality:ti-tj`` of every pair of primary test modes;
- constraints (J_k <= eps_k), with the limits of the case's standard (structures.acceptance):
  ``C:frequency:t`` of every secondary test mode, eps = (frequency_secondary / 100)^2;
  ``C:cross_orthogonality:ti-tj`` with ti or tj secondary, eps = off_diagonal^2;
  ``C:orthogonality:ti-tj`` of the tuned test modes, eps = orthogonality_off_diagonal^2;
  ``C:mass:q`` of every measured mass quantity q, eps = (MASS_TOLERANCE / 100)^2.
Of the case's own ``[tuning]`` terms the loop keeps the design-change terms of the objective
(``design:change:*``, the prior that regularises the update) and every constraint (a constraint
the case states replaces the generated limit of the same index); its other objective terms are
``pipeline tune``'s and are replaced by the selection's.

Stop rule (:func:`evaluate_targets`): the loop stops after stage n when, in every configuration,
every primary mode of stage n's selection has a paired test mode with |frequency error| within
the standard's primary limit and the cross-orthogonality off-diagonals among the primary test
modes, |S_p[i, k]| (i != k, S_p the paired matrix of structures.acceptance), are within its
off-diagonal limit -- or when there is no critical flutter root, hence nothing to tune for.
"""
from __future__ import annotations

import itertools

import numpy as np
import xarray as xr

from structures.acceptance import AcceptanceCriteria
from structures.common.errors import InputError

#: Largest relative error [%] of a measured mass quantity (weight, CG, inertia) held as a
#: constraint while the loop tunes for the primary modes.
MASS_TOLERANCE = 1.0


def tuned_test_modes(selection: xr.Dataset, configuration: str) -> tuple[list, list]:
    """(primary, secondary) GVT test modes of a configuration: those paired with the selection's
    primary / secondary FE modes (unpaired FE modes have test_mode 0 and are left out)."""
    sel = selection.sel(configuration=configuration)
    role, test = sel["role"].values.astype(str), sel["test_mode"].values.astype(int)
    primary = sorted({int(t) for r, t in zip(role, test) if r == "primary" and t > 0})
    secondary = sorted({int(t) for r, t in zip(role, test) if r == "secondary" and t > 0}
                       - set(primary))
    return primary, secondary


def loop_terms(selection: xr.Dataset, configurations, criteria: AcceptanceCriteria,
               measured_mass: dict) -> tuple[tuple, tuple, dict]:
    """Objective terms, constraints and tuned test modes of a loop stage (module docstring).

    Parameters
    ----------
    selection : xarray.Dataset
        The previous stage's selection.nc (``role``, ``test_mode`` on (configuration, mode)).
    configurations : sequence of str
    criteria : AcceptanceCriteria
        The case's standard.
    measured_mass : dict
        configuration -> {quantity: measured value} (the mass targets of the tuning problem).

    Returns
    -------
    (objective, constraints, test_modes)
        ``objective``: tuple of (index name, weight); ``constraints``: tuple of (index name, eps);
        ``test_modes``: configuration -> tuple of test modes to tune (primary + secondary).

    Raises
    ------
    InputError
        When no configuration has a primary mode paired with a test mode.
    """
    objective, constraints, test_modes = [], [], {}
    for c in configurations:
        primary, secondary = tuned_test_modes(selection, c)
        tuned = sorted(primary + secondary)
        if not tuned:
            continue
        test_modes[c] = tuple(tuned)
        objective += [(f"{c}:frequency:{t}", 1.0) for t in primary]
        objective += [(f"{c}:cross_orthogonality:{i}-{j}", 1.0)
                      for i, j in itertools.permutations(primary, 2)]
        constraints += [(f"{c}:frequency:{t}", (criteria.frequency_secondary / 100.0) ** 2)
                        for t in secondary if np.isfinite(criteria.frequency_secondary)]
        constraints += [(f"{c}:cross_orthogonality:{i}-{j}",
                         criteria.cross_orthogonality_off_diagonal ** 2)
                        for i, j in itertools.permutations(tuned, 2)
                        if (i in secondary or j in secondary)
                        and np.isfinite(criteria.cross_orthogonality_off_diagonal)]
        constraints += [(f"{c}:orthogonality:{i}-{j}", criteria.orthogonality_off_diagonal ** 2)
                        for i, j in itertools.combinations(tuned, 2)
                        if np.isfinite(criteria.orthogonality_off_diagonal)]
        constraints += [(f"{c}:mass:{q}", (MASS_TOLERANCE / 100.0) ** 2)
                        for q in measured_mass.get(c, {})]
    if not objective:
        raise InputError("the loop has no primary mode paired with a GVT mode in any "
                         "configuration, so there is nothing to tune for flutter. Fix: measure the "
                         "primary modes in the GVT, or lower [selection] primary.")
    return tuple(objective), tuple(constraints), test_modes


def _primary_block(corr: xr.Dataset, test_modes: list) -> np.ndarray:
    """|S_p| among ``test_modes``: S_p[i, k] = S[i, p(k)], p the pairing (structures.acceptance)."""
    rows = corr.sel(test_mode=test_modes)
    paired = rows["paired_fe_mode"].values
    return np.abs(rows["cross_orthogonality"].sel(fe_mode=paired).values)


def evaluate_targets(selection: xr.Dataset, correlations: dict, criteria: AcceptanceCriteria,
                     stage: int, last_stage: int) -> dict:
    """Whether the primary-mode targets hold after a stage (module docstring), as targets.json.

    Parameters
    ----------
    selection : xarray.Dataset
        The stage's selection.nc.
    correlations : dict
        configuration -> the stage's correlation.nc Dataset.
    criteria : AcceptanceCriteria
    stage, last_stage : int
        This stage and the last one the case allows ([loop] stages).

    Returns
    -------
    dict
        ``standard``, ``met`` (bool), ``stop_reason`` (str, "" when the loop goes on),
        ``failing``: list of {configuration, test_mode, fe_mode, check, value, limit}.
    """
    failing, n_primary = [], 0
    for c, corr in correlations.items():
        sel = selection.sel(configuration=c)
        roles = sel["role"].values.astype(str)
        fe_modes = selection["mode"].values[roles == "primary"]
        tests = sel["test_mode"].values.astype(int)[roles == "primary"]
        n_primary += fe_modes.size
        for fe, t in zip(fe_modes, tests):
            if t <= 0:
                failing.append({"configuration": c, "test_mode": None, "fe_mode": int(fe),
                                "check": "paired test mode", "value": None, "limit": None})
        primary = sorted({int(t) for t in tests if t > 0})
        for t in primary:
            err = float(corr["frequency_error"].sel(test_mode=t))
            if not abs(err) <= criteria.frequency_primary:
                failing.append({"configuration": c, "test_mode": t,
                                "fe_mode": int(corr["paired_fe_mode"].sel(test_mode=t)),
                                "check": "frequency error [%]", "value": err,
                                "limit": criteria.frequency_primary})
        block = _primary_block(corr, primary)
        for i, k in zip(*np.nonzero(~np.eye(len(primary), dtype=bool))):
            if not block[i, k] <= criteria.cross_orthogonality_off_diagonal:
                failing.append({"configuration": c, "test_mode": primary[i],
                                "fe_mode": int(corr["paired_fe_mode"].sel(test_mode=primary[k])),
                                "check": "cross-orthogonality off-diagonal",
                                "value": float(block[i, k]),
                                "limit": criteria.cross_orthogonality_off_diagonal})
    met = not failing
    if n_primary == 0:
        reason = "no critical flutter root in the analysed range: no primary mode to tune for"
    elif met:
        reason = f"every primary mode meets the {criteria.name} targets after stage {stage}"
    elif stage >= last_stage:
        reason = (f"the last stage allowed ([loop] stages = {last_stage}) ends with "
                  f"{len(failing)} primary-mode target(s) missed")
    else:
        reason = ""
    return {"standard": criteria.name, "stage": stage, "met": met or n_primary == 0,
            "stop_reason": reason, "failing": failing}


def tuning_problem(case, objective, constraints, test_modes=None, decks=None):
    """The structures.tuning problem of a case: its configurations' decks, GVT files and measured
    mass, the ``[tuning]`` design variables, and the given terms.

    Parameters
    ----------
    case : pipeline.case.Case
        With ``[tuning]`` and a gvt file for every configuration.
    objective, constraints : tuple of (index pattern, weight or eps)
    test_modes : dict, optional
        configuration -> test modes to tune (default: ``[tuning.configurations.C] test_modes``,
        else every GVT mode).
    decks : dict, optional
        configuration -> deck to start from (default: the configuration's deck).

    Returns
    -------
    structures.tuning.TuningProblem
    """
    from structures.bdf import read_model
    from structures.gvt import load_gvt
    from structures.tuning import TuningConfiguration, TuningProblem

    settings = case.tuning
    extra = dict(settings.per_configuration)
    configs = []
    for c in case.configurations:
        more = extra.get(c.name, {})
        modes = more.get("test_modes") if test_modes is None else test_modes.get(c.name)
        configs.append(TuningConfiguration(
            c.name, read_model((decks or {}).get(c.name, c.deck)), load_gvt(c.gvt),
            nmodes=c.nmodes or 30, mass=c.mass,
            test_modes=None if modes is None else tuple(modes),
            mass_targets=more.get("mass_targets", dict(c.measured_mass)),
            mass_references=more.get("mass_references", {})))
    return TuningProblem(tuple(configs), settings.variables, tuple(objective), tuple(constraints),
                         shape_method=settings.shape_method)


#: A constraint the start design already violates gets the limit J_k(start) x START_BUFFER (the
#: paper's practice, sec. V: a violated orthogonality term -0.143 was given the limit -0.144 "to
#: give some buffer value"; 1.02 on the squared index is 1 % on the term itself).
START_BUFFER = 1.02


def relaxed_at_start(problem, start=None):
    """The problem with every constraint that ``start`` violates relaxed to its start value.

    Constraint patterns are expanded to index names; J_k <= eps_k becomes
    J_k <= max(eps_k, START_BUFFER J_k(start)) (MAC: J_k >= min(eps_k, J_k(start) / START_BUFFER)),
    so the optimiser starts feasible and may not make those terms worse.

    Parameters
    ----------
    problem : structures.tuning.TuningProblem
    start : (nvar,) design values, optional (default the decks' values)

    Returns
    -------
    (structures.tuning.TuningProblem, list of (index name, eps, relaxed eps))
    """
    from dataclasses import replace

    from structures.tuning import Evaluator

    ev = Evaluator(problem)
    values, _ = ev.evaluate(ev.space.x0 if start is None else start)
    constraints, relaxed = [], []
    for i in ev.con_index:
        name, eps, value = ev.names[i], float(ev.limits[i]), float(values[i])
        if ev.lower_is_better[i] and value > eps:
            relaxed.append((name, eps, value * START_BUFFER))
            eps = value * START_BUFFER
        elif not ev.lower_is_better[i] and value < eps:
            relaxed.append((name, eps, value / START_BUFFER))
            eps = value / START_BUFFER
        constraints.append((name, eps))
    return replace(problem, constraints=tuple(constraints)), relaxed
