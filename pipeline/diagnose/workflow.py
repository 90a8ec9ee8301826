"""``diagnose()``: name the effect a model is missing (DESIGN.md section 5, issue 14 steps 1-6).

1. Preflight per configuration (:func:`pipeline.diagnose.evidence.build_reference`): analysis
   modes (``settings.nmodes`` or 2 x test + 6), pairing (MAC assignment at the sensors, or nearest
   frequency without shapes), test self-orthogonality with the SEREP analysis mass, shape noise
   (the test shapes' part outside the analysis modes' span), mass-property residual.
2. Residual vector with stated scales (:mod:`pipeline.diagnose.evidence`); every
   ``settings.holdout``-th paired mode is held out and judges the gap only, the held-out
   positions rotated by one per configuration (:func:`pipeline.diagnose.evidence.holdout_mask`)
   so that with several configurations every mode informs the naming somewhere. With one
   configuration a third of the modes stays unseen by the naming: an effect that moves only a
   held-out mode is missed (the gap report says so: its held-out error stays).
3. Nominal calibration and model-form flags (:mod:`pipeline.diagnose.calibrate`).
4. Screening of every candidate at several sizes, 5. refit of the best
   (:mod:`pipeline.diagnose.screen`) and the verdict (:func:`decide`).
6. Look again: the named effect, its fit continued to convergence
   (:func:`pipeline.diagnose.screen.polish`), is added and steps 4-5 repeat, up to
   ``settings.max_effects`` (a site already named is not offered again, alone or in a mirror
   pair). The gap is then cross-validated (:mod:`pipeline.diagnose.crossval`): the calibration
   and the named effects' fits are repeated on the other splits of the modes, so that every
   paired mode is judged once by a fit that did not see it.

The verdict of each round is :func:`pipeline.diagnose.verdict.decide`; an effect it names must
also fit inside its bounds (a parameter on a non-zero bound,
:func:`pipeline.diagnose.verdict.at_bound`, that the data press against, means the data want
more of it than the library's plausible range holds: the model-form signal of DESIGN.md section
5.2, not a finding; pressed: the unbounded Gauss-Newton step moves it outward and gains more
than the margin, :func:`pipeline.diagnose.screen.bound_release`) and beat
the best load path between two grids, an effect the library does not hold
(:mod:`pipeline.diagnose.loadpath`), by the margin, as it must beat the runner-up: a load path
that beats it by the margin makes the round ``unexplained``, one within the margin either way
``ambiguous`` (the effect or a load path; sensors at the path's two grids along the line joining
them separate them, the spring acting on their relative motion).
The overall verdict is ``effect`` when at least one effect was named, else the first round's;
a suspension identified from the test's suspension modes (:mod:`pipeline.diagnose.suspension`)
is added before the rounds and reported, but is the test's, not the structure's: it does not
make the verdict ``effect``.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Mapping

import numpy as np
import xarray as xr
from threadpoolctl import threadpool_limits

from pipeline.diagnose.calibrate import Problem, calibrate
from pipeline.diagnose.crossval import cross_validated, cross_validated_note
from pipeline.diagnose.detail import detailed
from pipeline.diagnose.effects import KINDS, candidates, neighbours
from pipeline.diagnose.evidence import SELF_ORTHOGONALITY_LIMIT, build_reference, chi_square
from pipeline.diagnose.gap import (EQUIVALENT_SIGMAS, gap_metrics, held_out_note,
                                   indistinguishable, separating_measurement)
from pipeline.diagnose.loadpath import best_load_path, load_path_measurement, outscores
from pipeline.diagnose.mirror import sites
from pipeline.diagnose.predictive import held_out_evidence, held_out_modes, kept_modes
from pipeline.diagnose.result import (CandidateScore, DiagnoseResult, EffectRecord,
                                      suspension_effects)
from pipeline.diagnose.screen import (bound_release, pick_for_refit, polish, refit, screen,
                                      signatures)
from pipeline.diagnose.suspension import FIT_LIMIT, hung_data, identify
from pipeline.diagnose.verdict import (SCATTER_SIGMAS, at_bound, decide, round_scores,
                                        within_scatter)
from structures.common.errors import InputError
from structures.massprops import check_measured_mass
from structures.modal import compute_modes
from structures.model import FEModel
from structures.modes import elastic_index, rigid_index
from structures.suspension import FREQUENCY_RATIO, RIGID_SHARE, without_suspension

#: Rigid-body modes added to twice the test modes for the default analysis mode count.
N_RIGID = 6


@dataclass(frozen=True)
class ConfigurationData:
    """One tested configuration.

    Attributes
    ----------
    name : str
    model : FEModel, the analysis model (nominal).
    gvt : xarray.Dataset, :mod:`structures.gvt` layout; ``shape`` may be absent (frequency-only).
    measured_mass : mapping or None, :func:`structures.massprops.read_measured_mass` layout.
    deck : Path, the deck (messages and :func:`pipeline.diagnose.effects.write_effect_deck`).
    """

    name: str
    model: FEModel
    gvt: xr.Dataset
    measured_mass: Mapping | None
    deck: Path

    def __post_init__(self):
        if not isinstance(self.model, FEModel):
            raise InputError(f"diagnose: configuration {self.name!r}: model is a "
                             f"{type(self.model).__name__}, not an FEModel. Fix: read the deck "
                             "with structures.bdf.read_model.")
        if not isinstance(self.gvt, xr.Dataset) or "frequency" not in self.gvt:
            raise InputError(f"diagnose: configuration {self.name!r}: the GVT data has no "
                             "frequency(mode). Fix: load it with structures.gvt.load_gvt.")
        if self.measured_mass is not None:
            object.__setattr__(self, "measured_mass", check_measured_mass(
                self.measured_mass, f"configuration {self.name} measured mass"))
        object.__setattr__(self, "deck", Path(self.deck))


@dataclass(frozen=True)
class DiagnoseSettings:
    """Settings of :func:`diagnose`.

    Attributes
    ----------
    kinds : effect kinds screened (:data:`pipeline.diagnose.effects.KINDS`).
    max_effects : look-again rounds (effects named at most).
    frequency_noise : test frequency standard deviation (fraction).
    shape_noise : test shape noise per DOF relative to the shape's RMS; None: estimated.
    holdout : every holdout-th paired mode (frequency order) of each configuration is held out.
    margin : BIC margin to name one candidate over the runner-up and over "none".
    refit : candidates refitted after the screening.
    nmodes : analysis modes (None: 2 x elastic test modes + 6: suspension modes not counted).
    model_scatter : relative scatter of the nominal section and mass properties that the few
        nominal parameters cannot follow: every section quantity of every property card and
        every CONM2 errs independently by it (:mod:`pipeline.diagnose.scatter`); it sets the
        residual's covariance (its scales and the correlation between modes).
    """

    kinds: tuple = KINDS
    max_effects: int = 3
    frequency_noise: float = 0.01
    shape_noise: float | None = None
    holdout: int = 3
    margin: float = 10.0
    refit: int = 6
    nmodes: int | None = None
    model_scatter: float = 0.03

    def __post_init__(self):
        kinds = (self.kinds,) if isinstance(self.kinds, str) else tuple(self.kinds)
        bad = [k for k in kinds if k not in KINDS]
        if bad or not kinds:
            raise InputError(f"diagnose: kinds {bad or '[]'} not in {list(KINDS)}. Fix: list some "
                             "of them.")
        object.__setattr__(self, "kinds", kinds)
        for name, low in (("max_effects", 1), ("holdout", 2), ("refit", 1)):
            value = getattr(self, name)
            if not isinstance(value, (int, np.integer)) or value < low:
                raise InputError(f"diagnose: {name} = {value!r} must be an integer >= {low}.")
        for name in ("frequency_noise", "margin"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and np.isfinite(value) and value > 0):
                raise InputError(f"diagnose: {name} = {value!r} must be a positive number.")
        for name in ("shape_noise",):
            value = getattr(self, name)
            if value is not None and not (np.isfinite(value) and value > 0):
                raise InputError(f"diagnose: {name} = {value!r} must be positive or None.")
        if not (np.isfinite(self.model_scatter) and self.model_scatter >= 0):
            raise InputError(f"diagnose: model_scatter = {self.model_scatter!r} must be >= 0.")
        if self.nmodes is not None and not (isinstance(self.nmodes, (int, np.integer))
                                            and self.nmodes > 0):
            raise InputError(f"diagnose: nmodes = {self.nmodes!r} must be a positive integer.")


# ------------------------------------------------------------------------------------ diagnose
def _overlaps(a, b) -> bool:
    return bool(set(a.grids) & set(b.grids) or set(a.elements) & set(b.elements)
                or set(a.properties) & set(b.properties))


def _chi2_split(problem: Problem, fit) -> tuple:
    """(chi2_modal, chi2_stated) of a refit: its training residual's modal rows and the rest
    (:meth:`pipeline.diagnose.calibrate.Problem.modal_rows`); they sum to ``fit.chi2``."""
    r, modal = problem.residual(fit.theta, fit.evaluations), problem.modal_rows()
    return chi_square(r[modal]), chi_square(r[~modal])


def _score_rows(problem: Problem, refits) -> list:
    """The (kind, location, chi2_modal, chi2_stated, n_params) rows of refitted candidates that
    :func:`pipeline.diagnose.verdict.decide` and :func:`round_scores` take."""
    return [(f.candidate.kind, f.candidate.location, *_chi2_split(problem, f), f.n_params)
            for f in refits]


def _prefer_one_side(problem: Problem, theta, effects, rows, fits, none, n_data: int,
                     margin: float, jacobian) -> tuple:
    """The round's fits without a best mirror pair that does not clearly beat its sides.

    A pair (:mod:`pipeline.diagnose.mirror`) claims the effect on both sides, one of its sites
    alone on one side only, with the same parameters: of two explanations within the margin the
    smaller change of the model is kept (parsimony; the margin of :func:`decide`, Kass & Raftery
    1995). When the best fit by :func:`pipeline.diagnose.verdict.round_scores` is a pair, its
    better-screened site is refitted (if it is not among the fits) and the pair is left out when
    that site's score is within ``margin`` of the pair's.

    Returns
    -------
    fits : list of Refitted, with the site's fit added and the pair left out where it loses.
    pair : Candidate or None, the pair left out.
    """
    if not fits:
        return fits, None
    n_modal = int(problem.modal_rows().sum())

    def scores(refits):
        return round_scores((*_chi2_split(problem, none), none.n_params),
                            _score_rows(problem, refits), n_data, n_modal=n_modal)[0]

    best = int(np.argmin(scores(fits)))
    pair = fits[best].candidate
    if pair.get("sites") is None:
        return fits, None
    own = sites(pair)
    if not any(f.candidate in own for f in fits):
        site_rows = [r for r in rows if r.candidate in own]
        if site_rows:
            site = refit(problem, theta, effects, max(site_rows, key=lambda r: r.drop),
                         n_data=n_data, jacobian_theta=jacobian)
            fits = fits + ([site] if site is not None else [])
    score = scores(fits)
    sides = [score[i] for i, f in enumerate(fits) if f.candidate in own]
    if sides and min(sides) < score[best] + margin:
        return [f for i, f in enumerate(fits) if i != best], pair
    return fits, None


def unnamed(cands, effects) -> list:
    """The candidates none of whose sites is already named: a site is named once, a joint once
    per rigid element (a named joint's rigid element stays rigid on a new grid, so its joint
    candidates of the next round have a location of their own).

    Parameters
    ----------
    cands : sequence of Candidate, a round's library.
    effects : sequence of (Candidate, values), the effects named so far.
    """
    named = {(s.kind, s.location) for c, _ in effects for s in sites(c)}
    hung = {s.location.elements[0] for c, _ in effects for s in sites(c)
            if s.kind == "joint_flexibility"}
    return [c for c in cands if not any(
        (s.kind, s.location) in named
        or (s.kind == "joint_flexibility" and s.location.elements[0] in hung) for s in sites(c))]


def _say(progress, text: str) -> None:
    if progress is not None:
        progress(text)


def preflight(configurations, settings: DiagnoseSettings = DiagnoseSettings()) -> tuple:
    """Every data check of :func:`diagnose` that can fail, without calibration or screening.

    Analysis modes of every configuration, pairing, enough elastic modes and sensor DOFs, the
    shape-noise estimate, test self-orthogonality and the measured-mass residual scales (step 1
    of the module docstring), so that a caller (the CLI) can reject bad data before any stage
    runs.

    Parameters
    ----------
    configurations : sequence of ConfigurationData
    settings : DiagnoseSettings

    Returns
    -------
    refs : tuple of :class:`pipeline.diagnose.evidence.Reference`, one per configuration.
    notes : tuple of str, what the data can and cannot tell.

    Raises
    ------
    InputError
        No or repeated configurations, wrong settings, too few analysis modes or sensor DOFs.
    """
    configurations = tuple(configurations)
    _check_inputs(configurations, settings)
    refs, notes, _ = _checked(configurations, settings)
    return refs, notes


def _check_inputs(configurations: tuple, settings) -> None:
    if not configurations:
        raise InputError("diagnose: no configurations. Fix: give at least one ConfigurationData.")
    names = [c.name for c in configurations]
    if len(set(names)) != len(names):
        raise InputError(f"diagnose: configuration names {names} repeat. Fix: name each once.")
    if not isinstance(settings, DiagnoseSettings):
        raise InputError("diagnose: settings must be a DiagnoseSettings.")


def _checked(configurations, settings) -> tuple:
    """(refs, notes, hung) of :func:`preflight`, ``hung`` each configuration's suspension modes
    (a GVT Dataset, or None)."""
    notes: list = []
    hung: list = []
    with threadpool_limits(limits=1):
        refs = _preflight(configurations, settings, notes, hung)
    return tuple(refs), tuple(notes), tuple(hung)


def _preflight(configurations, settings: DiagnoseSettings, notes: list, hung: list):
    """The references of :func:`preflight`; ``hung`` receives each configuration's suspension
    modes (a GVT Dataset, or None; attribute ``n_rigid``: the model's rigid-body modes)."""
    refs = []
    for rotation, data in enumerate(configurations):
        nmodes = settings.nmodes or 2 * data.gvt.sizes["mode"] + N_RIGID
        modes = compute_modes(data.model, nmodes)
        gvt, suspended = _without_suspension(data, modes, notes)
        if settings.nmodes is None and suspended is not None:
            nmodes = 2 * gvt.sizes["mode"] + N_RIGID          # counted on the elastic test modes
            modes = modes.isel(mode=slice(0, nmodes))
        hung.append(suspended if suspended is None else
                    suspended.assign_attrs(n_rigid=int(rigid_index(modes).size)))
        n_test = gvt.sizes["mode"]
        if elastic_index(modes).size < n_test:
            raise InputError(f"diagnose: configuration {data.name}: {n_test} test modes but only "
                             f"{elastic_index(modes).size} elastic analysis modes. Fix: raise "
                             "[diagnose] nmodes.")
        ref, facts = build_reference(
            data.name, data.model, gvt, data.measured_mass, modes,
            frequency_noise=settings.frequency_noise,
            shape_noise_value=settings.shape_noise, model_scatter=settings.model_scatter,
            holdout=settings.holdout, nmodes=nmodes, rotation=rotation)
        refs.append(ref)
        if ref.has_shapes:
            notes.append(f"{data.name}: {n_test} test modes, {ref.sensor_index.size} sensor DOFs, "
                         f"shape noise {100 * facts['shape_noise']:.1f} % of the RMS (median), "
                         f"test self-orthogonality largest off-diagonal "
                         f"{_rounded(facts['self_orthogonality'])}, "
                         f"paired MAC min {min(facts['mac']):.2f}.")
            if facts["unmatched"]:
                notes.append(f"{data.name}: test modes {facts['unmatched']} have no counterpart "
                             "among the analysis modes (their shapes lie outside the modes' span "
                             "at the sensors): a local mode the model lacks.")
            if facts["self_orthogonality"] is not None and \
                    facts["self_orthogonality"] > SELF_ORTHOGONALITY_LIMIT:
                notes.append(f"{data.name}: the test modes are not orthogonal in the analysis mass "
                             f"(largest off-diagonal {facts['self_orthogonality']:.2f}): noisy or "
                             "aliased shapes, or a mass distribution the model lacks.")
        else:
            notes.append(f"{data.name}: frequency-only data ({n_test} modes): paired by nearest "
                         "frequency; the shapes cannot tell where along a symmetric structure, "
                         "nor a member from a joint at one spot.")
        if not ref.mass_scale:
            notes.append(f"{data.name}: no measured mass properties: a missing mass is seen only "
                         "through the frequencies.")
    return refs


def _without_suspension(data, modes: xr.Dataset, notes: list) -> tuple:
    """(the configuration's test modes without its suspension modes, the suspension modes or
    None) (:func:`structures.suspension.without_suspension`: shapes at the sensors, placed at
    the model's grids, that are rigid-body motions below the lowest elastic analysis frequency;
    frequency-only, modes below ``FREQUENCY_RATIO`` of it), set aside with a note. Only a model
    with rigid-body modes is hung on a suspension: a clamped one keeps every test mode."""
    gvt = data.gvt
    position = None
    if "shape" in gvt:
        grids = data.model.grids
        position = grids.xyz[grids.index(gvt["grid"].values, card="GVT sensor grid",
                                         filename=gvt.attrs.get("source") or None)]
    try:
        kept, hung = without_suspension(modes, gvt, position=position)
    except InputError as exc:
        raise InputError(f"configuration {data.name}: {exc}") from None
    if not hung.sizes["mode"]:
        return gvt, None
    f_fe = modes["frequency"].values[elastic_index(modes)]
    f = hung["frequency"].values
    why = (f"their shapes are rigid-body motions at the sensors (at least {100 * RIGID_SHARE:.0f} "
           f"% of each shape) below the lowest elastic analysis frequency, {f_fe.min():.3g} Hz"
           if "shape" in gvt else
           f"below {FREQUENCY_RATIO:g} x the lowest elastic analysis frequency, "
           f"{f_fe.min():.3g} Hz")
    notes.append(f"{data.name}: test modes {hung['mode'].values.tolist()} ({f.min():.3g}-"
                 f"{f.max():.3g} Hz) are "
                 f"suspension modes, {why}: left out of the pairing (no elastic mode of the "
                 "model matches them); with shapes they identify the suspension.")
    return kept, hung


def _rounded(value):
    """``value`` to 3 decimals, None as it is."""
    return None if value is None else round(value, 3)


def _table(problem: Problem, r0, rows, refits, none, n_data: int, n_candidates: int) -> tuple:
    """The first round's ranked candidates by the scores :func:`decide` compared
    (:func:`round_scores`: refitted ones from their refit, the rest from their linearised
    residual r0 + S x (:class:`pipeline.diagnose.screen.Screened`: S x is the residual's change
    at x for every kind) with the same modal dispersion c, "none" with its prior odds), minus
    the best."""
    modal = problem.modal_rows()
    scores, none_score, c = round_scores((*_chi2_split(problem, none), none.n_params),
                                         _score_rows(problem, refits), n_data, n_candidates,
                                         n_modal=int(modal.sum()))
    scored = [(b, fit.candidate, True) for b, fit in zip(scores, refits)]
    done = {id(fit.candidate) for fit in refits}
    for row in rows:
        if id(row.candidate) not in done:
            p = len(row.candidate.parameters) + problem.n_theta
            r = r0 + row.signature @ row.values                              # linearised residual
            scored.append((chi_square(r[modal]) / c + chi_square(r[~modal]) + p * np.log(n_data),
                           row.candidate, False))
    scored.append((none_score, None, True))
    scored.sort(key=lambda s: s[0])
    best = scored[0][0]
    return tuple(CandidateScore(c.kind if c else "none", c.location.as_dict() if c else
                                {"grids": [], "elements": [], "properties": []}, float(b - best),
                                c.label if c else "nothing missing", refitted)
                 for b, c, refitted in scored)


def diagnose(configurations, settings: DiagnoseSettings = DiagnoseSettings(), *,
             progress=None) -> DiagnoseResult:
    """Name the effect(s) the model is missing (module docstring).

    Parameters
    ----------
    configurations : sequence of ConfigurationData
        The tested configurations (one structure in several loadings).
    settings : DiagnoseSettings
    progress : callable(str), optional
        Receives progress notes.

    Returns
    -------
    DiagnoseResult
    """
    configurations = tuple(configurations)
    t0 = time.perf_counter()
    _check_inputs(configurations, settings)
    refs, notes, hung = _checked(configurations, settings)
    notes = list(notes)
    with threadpool_limits(limits=1):
        problem = Problem.build(refs, [c.model for c in configurations], settings.model_scatter)
        _say(progress, "calibrating the nominal parameters")
        cal = calibrate(problem)
        n_data = cal.n_data
        notes += [f"calibration: {name} {100 * t:+.1f} %"
                  for name, t in zip(problem.names, cal.theta)]
        notes += list(cal.flags)
        gap_before = gap_metrics(problem, cal.evaluations)
        effects, records, rounds = [], [], []
        theta, none_evs = cal.theta, cal.evaluations
        gap_after = gap_before                                  # nothing named: the same model
        suspension = None
        found = _suspension(configurations, refs, hung, settings, problem, theta, notes)
        if found is not None:
            _say(progress, "adding the suspension")
            best, fits = found
            effects = best.effects()
            hung_none = refit(problem, theta, effects, None, n_data=n_data,
                              jacobian_theta=cal.jacobian)
            lead = fits[1].bic - best.bic if len(fits) > 1 else float("inf")
            records += [EffectRecord(c, v, lead) for c, v in effects]
            theta, none_evs = hung_none.theta, hung_none.evaluations
            gap_after = gap_metrics(problem, none_evs)
            suspension = _suspension_record(best, fits, gap_after)
            notes.append(_suspension_note(best, fits, settings.margin))
        table, separating, first = (), None, None
        for k in range(settings.max_effects):
            _say(progress, f"round {k + 1}: screening")
            model0 = problem.model(0, theta, effects)
            cands = unnamed(candidates(model0, settings.kinds), effects)
            r0, signed, skipped = signatures(problem, theta, effects, none_evs, cands,
                                             progress=progress)
            if skipped:
                notes.append(f"round {k + 1}: {len(skipped)} candidates could not be applied to "
                             f"every configuration (first: {skipped[0]}).")
            rows = screen(r0, signed)
            _say(progress, f"round {k + 1}: refitting")
            none = refit(problem, theta, effects, None, n_data=n_data,
                         jacobian_theta=cal.jacobian) if effects else _none_fit(problem, cal,
                                                                                n_data)
            fits = [refit(problem, theta, effects, row, n_data=n_data, jacobian_theta=cal.jacobian)
                    for row in pick_for_refit(rows, settings.refit)]
            fits = [f for f in fits if f is not None]
            small = [within_scatter(model0, f.candidate, f.values, settings.model_scatter)
                     for f in fits]
            if any(small):
                labels = ", ".join(f.candidate.label for f, s in zip(fits, small) if s)
                notes.append(f"round {k + 1}: {labels} left out: fitted within "
                             f"{SCATTER_SIGMAS:g} x the nominal scatter of what they change.")
                fits = [f for f, s in zip(fits, small) if not s]
            fits, pair = _prefer_one_side(problem, theta, effects, rows, fits, none, n_data,
                                          settings.margin, cal.jacobian)
            if pair is not None:
                notes.append(f"round {k + 1}: {pair.kind} {pair.label} left out: it does not "
                             f"beat one of its sides alone by the margin {settings.margin:g}.")
            model_k = model0

            def near(a, b):
                return _overlaps(neighbours(model_k, a), b)

            modes_none, entries = held_out_modes(problem, none.evaluations)
            modes = [held_out_modes(problem, f.evaluations)[0] for f in fits]
            scored = ((*_chi2_split(problem, none), none.n_params), _score_rows(problem, fits),
                      int(problem.modal_rows().sum()))
            alike = cache(lambda i, j: indistinguishable(problem, fits[i], fits[j]))
            verdict, best, runner, lead, reason, c = decide(
                scored[0], scored[1], settings.margin, near, n_data, len(cands),
                n_modal=scored[2], held_out=(modes_none, modes, entries), alike=alike)
            same = [] if best is None else [fits[i].candidate.label for i in range(len(fits))
                                            if i != best and alike(best, i)]
            if same and reason != "no_gain":
                notes.append(f"round {k + 1}: {fits[best].candidate.kind} "
                             f"{fits[best].candidate.label} and {', '.join(same)} predict every "
                             "paired frequency and every DOF's shape within "
                             f"{EQUIVALENT_SIGMAS:g} sigma of each other: one explanation, no "
                             "measurement separates them; the best fit stands for them.")
            path = None
            if verdict == "effect":
                cand = fits[best].candidate
                bound = at_bound(cand, fits[best].values)
                outward, gain = (bound_release(problem, effects, fits[best],
                                               jacobian_theta=cal.jacobian)
                                 if bound else (False, 0.0))
                if bound and outward and gain / c > settings.margin:
                    verdict = "unexplained"
                    notes.append(f"round {k + 1}: {cand.kind} {cand.label} fits best but "
                                 f"{', '.join(bound)} sits on its bound and the data want "
                                 f"more (released, chi^2 falls by {gain:.1f} along the "
                                 f"unbounded Gauss-Newton step, {gain / c:.1f} after the "
                                 f"dispersion {c:.2f}): more than the library's range of that "
                                 "effect; not named (a different or larger effect).")
                elif bound:
                    notes.append(f"round {k + 1}: {cand.kind} {cand.label}: "
                                 f"{', '.join(bound)} sits on its bound, but the data do not "
                                 "press against it (released, the unbounded Gauss-Newton step "
                                 + (f"gains {gain:.1f} in chi^2, {gain / c:.1f} after the "
                                    f"dispersion, below the margin {settings.margin:g})."
                                    if outward else "moves it inward)."))
            if verdict == "effect":
                found = best_load_path(problem, theta, effects, none_evs, r0)
                verdict, path = _against_path(found, problem, scored, best, n_data, len(cands),
                                              settings.margin)
                rich = (detailed(problem, effects, fits[best], n_data=n_data,
                                 jacobian_theta=cal.jacobian) if verdict == "ambiguous" else None)
                if rich is not None:
                    row = _score_rows(problem, [rich])
                    again = _against_path(found, problem, (scored[0], scored[1][:best] + row +
                                                           scored[1][best + 1:], scored[2]),
                                          best, n_data, len(cands), settings.margin)
                    notes.append(f"round {k + 1}: {fits[best].candidate.kind} "
                                 f"{fits[best].candidate.label} against the load path between "
                                 f"grids {path[0].grids[0]} and {path[0].grids[1]} within the "
                                 "margin: with one compliance per CBUSH component (chi^2 "
                                 f"{fits[best].chi2:.1f} -> {rich.chi2:.1f}) it scores "
                                 f"{again[1][2]:.1f} against the path's {again[1][1]:.1f}"
                                 + (", named." if again[0] == "effect" else "."))
                    if again[0] == "effect":
                        verdict, path = again
                        fits[best] = rich
                        modes[best] = held_out_modes(problem, rich.evaluations)[0]
            rounds.append(_round_record(k, verdict, fits, best, runner, none,
                                        (modes_none, modes, entries), n_data, scored + (c,),
                                        path, same, reason=reason, margin=settings.margin))
            if path is not None and verdict in ("unexplained", "ambiguous"):
                cand = fits[best].candidate
                a, b = path[0].grids
                how, end = (("better", ": the effect is outside the library.")
                            if verdict == "unexplained" else ("as well, within the margin", "."))
                notes.append(f"round {k + 1}: {cand.kind} {cand.label} is not named: a load "
                             f"path the library does not hold, a spring between grids {a} and "
                             f"{b} (k = {path[0].stiffness:.4g}), fits the training data {how} "
                             f"(score {path[1]:.1f} against {path[2]:.1f}){end}")
            if reason == "held_out":
                cand, record = fits[best].candidate, rounds[-1]["best"]
                kept = np.asarray(record["held_out_modes_kept"])
                notes.append(f"round {k + 1}: {cand.kind} {cand.label} fits the training modes "
                             f"(chi^2 {none.chi2:.0f} -> {fits[best].chi2:.0f}) but not the "
                             f"{int(kept.sum())} held-out modes either model reproduces (chi^2 "
                             f"{modes_none[kept].sum():.0f} -> {modes[best][kept].sum():.0f}, "
                             f"evidence {record['held_out_evidence']:.1f}; per mode in the round "
                             "record): it compensates for something else; not named.")
            if reason == "past_veto" and verdict == "effect":
                cand, named = fits[best].candidate, rounds[-1]["best"]
                notes.append(f"round {k + 1}: the held-out modes contradict "
                             f"{'; '.join(rounds[-1]['vetoed'])} (a compensation the training "
                             "modes prefer); "
                             f"{cand.kind} {cand.label}, the best fit they do not contradict, "
                             f"beats the rest by {lead:.1f} and the held-out modes support it "
                             f"(evidence {named['held_out_evidence']:+.1f}): named. The held-out "
                             "modes took part in naming it, so its gap on them is no blind "
                             "check.")
            if k == 0:
                first = verdict
                table = _table(problem, r0, rows, fits, none, n_data, len(cands))
            if verdict == "ambiguous" and not effects:
                separating = (load_path_measurement(fits[best].candidate, path[0])
                              if path is not None else
                              separating_measurement(problem, fits[best], fits[runner]))
            if verdict != "effect":
                break
            chosen = fits[best]
            rich = detailed(problem, effects, chosen, n_data=n_data, jacobian_theta=cal.jacobian)
            if rich is not None:
                notes.append(f"round {k + 1}: {chosen.candidate.kind} {chosen.candidate.label} "
                             f"added with one compliance per CBUSH component: chi^2 "
                             f"{chosen.chi2:.1f} -> {rich.chi2:.1f}, BIC {chosen.bic:.1f} -> "
                             f"{rich.bic:.1f}.")
                rounds[-1]["detailed"] = {"parameters": dict(zip(rich.candidate.parameters,
                                                                 map(float, rich.values))),
                                          "chi2": float(rich.chi2), "bic": float(rich.bic),
                                          "named_chi2": float(chosen.chi2),
                                          "named_bic": float(chosen.bic)}
                chosen = rich
            polished = polish(problem, effects, chosen, n_data=n_data, jacobian_theta=cal.jacobian)
            if polished is not chosen:
                notes.append(f"round {k + 1}: {chosen.candidate.kind} {chosen.candidate.label} "
                             f"fitted to convergence: chi^2 {chosen.chi2:.6g} -> "
                             f"{polished.chi2:.6g}.")
                rounds[-1]["polished"] = {
                    "parameters": dict(zip(polished.candidate.parameters,
                                           map(float, polished.values))),
                    "chi2": float(polished.chi2), "fitted_chi2": float(chosen.chi2)}
                chosen = polished
            gap_after = rounds[-1]["gap"] = gap_metrics(problem, chosen.evaluations)
            rounds[-1]["nominal"] = {n: float(t) for n, t in zip(problem.names, chosen.theta)}
            records.append(EffectRecord(chosen.candidate, chosen.values, lead))
            effects.append((chosen.candidate, chosen.values))
            theta, none_evs = chosen.theta, chosen.evaluations
    n_hung = suspension_effects(suspension)
    verdict = "effect" if len(records) > n_hung else first      # the structure's, not the test's
    if records and (note := held_out_note(gap_before, gap_after)):
        notes.append(note)
    if records:
        _say(progress, "cross-validating the gap")
        with threadpool_limits(limits=1):
            cv = cross_validated(problem, settings.holdout, gap_before, gap_after,
                                 effects[:n_hung], effects[n_hung:])
        if cv is None:
            notes.append("gap: not cross-validated: a refit on another split of the modes could "
                         "not be analysed at its start.")
        else:
            gap_before, gap_after = {**gap_before, **cv[0]}, {**gap_after, **cv[1]}
            notes.append(cross_validated_note(gap_before, gap_after, settings.holdout))
    notes.append(f"diagnose took {time.perf_counter() - t0:.1f} s "
                 f"({len(rounds)} round{'s' if len(rounds) > 1 else ''}).")
    return DiagnoseResult(verdict=verdict, effects=tuple(records), candidates=table,
                          gap_before=gap_before, gap_after=gap_after, notes=tuple(notes),
                          separating_measurement=separating,
                          nominal={n: float(t) for n, t in zip(problem.names, theta)},
                          rounds=tuple(rounds),
                          calibrated={n: float(t) for n, t in zip(problem.names, cal.theta)},
                          suspension=suspension)


def _suspension(configurations, refs, hung, settings: DiagnoseSettings, problem: Problem,
                theta, notes: list):
    """(best, fits) of :func:`pipeline.diagnose.suspension.identify` on the configurations whose
    test lists suspension modes with shapes, or None (with a note when there are suspension
    modes but they cannot be used)."""
    used = [i for i, h in enumerate(hung) if h is not None and "shape" in h]
    if not any(h is not None for h in hung):
        return None
    if "boundary_stiffness" not in settings.kinds:
        notes.append("the test's suspension modes identify no suspension: boundary_stiffness "
                     "is not among the kinds screened.")
        return None
    if not used:
        notes.append("the suspension modes have no shapes: where the suspension acts cannot be "
                     "told, and it is not identified (its stiffening of the elastic modes is "
                     "left to the rounds).")
        return None
    short = [(configurations[i].name, hung[i].sizes["mode"], hung[i].attrs["n_rigid"])
             for i in used if hung[i].sizes["mode"] < hung[i].attrs["n_rigid"]]
    if short:
        name, n, n_rigid = short[0]
        notes.append(f"{name}: {n} suspension modes where the model has {n_rigid} rigid-body "
                     "motions, and every suspension of the hypotheses holds all of them: the "
                     "missing one is held by something stiffer than the suspension (a support: "
                     "the rounds look for it) or was not measured; the suspension is not "
                     "identified from them.")
        return None
    held = {i: hung[i].isel(mode=hung[i]["frequency"].values > 0.0) for i in used}
    if any(held[i].sizes["mode"] < hung[i].sizes["mode"] for i in used):
        notes.append("suspension modes at 0 Hz (a rigid-body motion the suspension does not "
                     "hold) are left out of the suspension's identification.")
    used = [i for i in used if held[i].sizes["mode"]]
    if not used:
        return None
    models = [problem.model(i, theta) for i in used]
    data = [hung_data(configurations[i].name, held[i], m.grids,
                      float(np.median(refs[i].shape_sigma)) if refs[i].shape_sigma is not None
                      else settings.shape_noise or 0.05, configurations[i].measured_mass)
            for i, m in zip(used, models)]
    best, fits = identify(models, data, frequency_noise=settings.frequency_noise)
    if best.chi2 > FIT_LIMIT * best.n_data:
        notes.append(f"the suspension modes fit no suspension of the hypotheses (best "
                     f"{best.label}: chi^2 {best.chi2:.0f} over {best.n_data} data, more than "
                     f"{FIT_LIMIT:g} per datum): a support they do not hold (one-sided, or "
                     "more sites); none added, the rounds look at the free model.")
        return None
    return best, fits


def _suspension_record(best, fits, gap) -> dict:
    """The JSON record of the identified suspension (DiagnoseResult ``suspension``)."""
    return {"sites": [list(site) for site in best.sites],
            "stiffness": best.stiffness.tolist(), "chi2": best.chi2, "bic": best.bic,
            "n_data": best.n_data,
            "frequencies": {name: {"test": t.tolist(), "model": m.tolist()}
                            for name, (t, m) in best.frequencies.items()},
            "alternatives": [{"label": f.label, "bic": f.bic} for f in fits[1:]],
            "gap": gap}


def _suspension_note(best, fits, margin: float) -> str:
    """What the suspension fit found, and the hypotheses within the margin of it."""
    springs = "; ".join(f"{'+'.join(map(str, site))}: k_x, k_y, k_z = "
                        + ", ".join(f"{v:.4g}" for v in k)
                        for site, k in zip(best.sites, best.stiffness))
    rivals = [f.label for f in fits[1:] if f.bic - best.bic <= margin]
    return (f"suspension from the test's suspension modes: grounded springs at {springs} "
            f"(chi^2 {best.chi2:.1f} over {best.n_data} data; the runner-up, "
            + (f"{fits[1].label}, scores {fits[1].bic - best.bic:.1f} higher" if len(fits) > 1
               else "none") + "); added before the rounds"
            + (f"; {', '.join(rivals)} fit within the margin {margin:g}: where the suspension "
               "acts is not certain." if rivals else "."))


def _none_fit(problem: Problem, cal, n_data: int):
    from pipeline.diagnose.evidence import bic
    from pipeline.diagnose.screen import Refitted

    return Refitted(None, np.zeros(0), cal.theta, cal.chi2, bic(cal.chi2, len(cal.theta), n_data),
                    len(cal.theta), cal.evaluations)


def _against_path(found, problem: Problem, scored, best: int, n_data: int, n_candidates: int,
                  margin: float) -> tuple:
    """(verdict, (LoadPath, its score, the named effect's score) or None): "unexplained" when the
    best load path ``found`` (:func:`pipeline.diagnose.loadpath.best_load_path`, None: no path)
    beats the named effect (fit ``best`` of the round's ``scored`` rows) by the margin,
    "ambiguous" when neither beats the other by it, else "effect"; both scored at the modal
    dispersion of those rows (:func:`pipeline.diagnose.verdict.round_scores`)."""
    if found is None:
        return "effect", None
    scores, _, c = round_scores(scored[0], scored[1], n_data, n_candidates, n_modal=scored[2])
    beats, score = outscores(found, float(scores[best]), problem.modal_rows(), c,
                             problem.n_theta, n_data, n_candidates, margin)
    named = float(scores[best])
    verdict = "unexplained" if beats else ("effect" if named + margin < score else "ambiguous")
    return verdict, (found, score, named)


def _round_record(k: int, verdict: str, fits, best, runner, none, held_out, n_data: int,
                  scored, path=None, alike=(), *, reason: str = "", margin: float = np.inf
                  ) -> dict:
    """The JSON record of round k (:class:`pipeline.diagnose.result.DiagnoseResult` ``rounds``).

    ``held_out`` is (modes_none, per fit modes, entries) of
    :func:`pipeline.diagnose.predictive.held_out_modes`; ``scored`` is (the "none" row, the fits'
    rows, n_modal, c) that :func:`pipeline.diagnose.verdict.decide` took and returned (rows
    (..., chi2_modal, chi2_stated, n_params), c the modal dispersion); ``path`` is
    (LoadPath, its score, the named effect's score) of :func:`_against_path`, or None when
    the round named nothing; ``alike`` the labels of the fits that predict the same data as the
    best (:func:`pipeline.diagnose.gap.indistinguishable`); ``reason`` as
    :func:`pipeline.diagnose.verdict.decide` gave it; ``vetoed`` lists the fits whose held-out
    evidence is below -``margin``.
    """
    modes_none, modes, entries = held_out
    none_row, rows, n_modal, c = scored

    def entry(i):
        if i is None:
            return None
        f = fits[i]
        return {"kind": f.candidate.kind, "label": f.candidate.label, "bic": f.bic,
                "chi2": f.chi2, "chi2_modal": rows[i][2], "n_params": f.n_params,
                "held_out_chi2": float(modes[i].sum()),
                "held_out_modes_chi2": modes[i].tolist(),
                "held_out_modes_kept": kept_modes(modes_none, modes[i], entries).tolist(),
                "held_out_evidence": held_out_evidence(modes_none, modes[i], entries, c),
                "parameters": dict(zip(f.candidate.parameters, map(float, f.values)))}
    fitted = [entry(i) for i in range(len(fits))]
    return {"round": k + 1, "verdict": verdict, "reason": reason,
            "vetoed": [e["label"] for e in fitted if e["held_out_evidence"] < -margin],
            "n_data": n_data, "n_modal": n_modal,
            "dispersion": c,
            "n_held_out": int(np.sum(entries)), "held_out_modes_entries": entries.tolist(),
            "none_bic": none.bic,
            "none_chi2": none.chi2, "none_chi2_modal": none_row[0],
            "none_n_params": none.n_params,
            "none_held_out_chi2": float(modes_none.sum()),
            "none_held_out_modes_chi2": modes_none.tolist(),
            "gap": None, "nominal": None, "detailed": None, "best": entry(best),
            "runner_up": entry(runner),
            "alike": list(alike),
            "fits": fitted,
            "load_path": None if path is None else {
                "grids": list(path[0].grids), "stiffness": path[0].stiffness,
                "chi2": chi_square(path[0].residual), "n_pairs": path[0].n_pairs,
                "score": path[1], "named_score": path[2]}}
