"""``diagnose()``: name the effect a model is missing (DESIGN.md section 5, issue 14 steps 1-6).

1. Preflight per configuration (:mod:`pipeline.diagnose.preflight`): analysis modes
   (``settings.nmodes`` or 2 x test + 6), pairing (MAC assignment at the sensors, or nearest
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
   (:func:`pipeline.diagnose.refit.polish`), is added and steps 4-5 repeat, up to
   ``settings.max_effects`` (a site already named is not offered again, alone or in a mirror
   pair; a later round's fit must also be supported by the held-out modes by the margin,
   :func:`decide`'s ``confirm``). The gap is then cross-validated
   (:mod:`pipeline.diagnose.crossval`): the calibration and the named effects' fits are
   repeated on the other splits of the modes, so that every paired mode is judged once by a
   fit that did not see it.

The verdict of each round is :func:`pipeline.diagnose.verdict.decide`; an effect it names must
also fit inside its bounds (a parameter on a non-zero bound,
:func:`pipeline.diagnose.verdict.at_bound`, that the data press against, means the data want
more of it than the library's plausible range holds: the model-form signal of DESIGN.md section
5.2, not a finding; pressed: the unbounded Gauss-Newton step moves it outward and gains more
than the margin, :func:`pipeline.diagnose.refit.bound_release`) and beat
the best load path between two grids, an effect the library does not hold
(:mod:`pipeline.diagnose.loadpath`), by the margin, as it must beat the runner-up: a load path
that beats it by the margin makes the round ``unexplained``, one within the margin either way
``ambiguous`` (the effect or a load path; sensors at the path's two grids along the line joining
them separate them, the spring acting on their relative motion). Last, the named effect is
refitted on the other splits of the paired modes (:mod:`pipeline.diagnose.crossval`, the refits
the cross-validated gap is made of): when most splits do not support it
(:func:`pipeline.diagnose.crossval.stable`), the name rests on which modes were held out and the
round is ``unexplained`` (reason ``unstable``).
The overall verdict is ``effect`` when at least one effect was named, else the first round's;
a suspension identified from the test's suspension modes (:mod:`pipeline.diagnose.suspension`)
is added before the rounds and reported, but is the test's, not the structure's: it does not
make the verdict ``effect``.
"""
from __future__ import annotations

import time
from functools import cache

import numpy as np
from threadpoolctl import threadpool_limits

from pipeline.diagnose.calibrate import Problem, calibrate
from pipeline.diagnose.crossval import (cross_validated, cross_validated_note, extend,
                                        open_splits, stability_note, stable, support_records)
from pipeline.diagnose.detail import detailed, form_text, located
from pipeline.diagnose.effects import candidates, neighbours
from pipeline.diagnose.gap import (EQUIVALENT_SIGMAS, gap_metrics, held_out_note,
                                   indistinguishable, offdiag_note, separating_measurement)
from pipeline.diagnose.linearised import standard_errors
from pipeline.diagnose.loadpath import best_load_path, load_path_measurement
from pipeline.diagnose.mirror import sites
from pipeline.diagnose.predictive import held_out_evidence, held_out_modes
from pipeline.diagnose.preflight import DiagnoseSettings, check_inputs, checked
from pipeline.diagnose.result import DiagnoseResult, EffectRecord, suspension_effects
from pipeline.diagnose.round_notes import (bound_note, held_out_veto_note, load_path_note,
                                           located_note, past_veto_note, reversal_note,
                                           rich_path_note, unconfirmed_note,
                                           undetermined_note)
from pipeline.diagnose.rounds import (against_path, chi2_split, none_fit, ranking_table,
                                      round_record, score_rows, sites_elsewhere)
from pipeline.diagnose.refit import bound_release, polish, refit
from pipeline.diagnose.screen import pick_for_refit, screen, signatures
from pipeline.diagnose.suspension import FIT_LIMIT, hung_data, identify
from pipeline.diagnose.verdict import SCATTER_SIGMAS, at_bound, decide, round_scores, within_scatter


# ------------------------------------------------------------------------------------ diagnose
def _overlaps(a, b) -> bool:
    return bool(set(a.grids) & set(b.grids) or set(a.elements) & set(b.elements)
                or set(a.properties) & set(b.properties))


def _form_record(fit, rich) -> dict:
    """A joint tried for the named location (:func:`pipeline.diagnose.detail.located`): its label,
    two-parameter chi^2 and BIC, and those of its detailed form (None when that does not lower
    the BIC)."""
    return {"label": fit.candidate.label, "chi2": float(fit.chi2), "bic": float(fit.bic),
            "detailed_chi2": None if rich is None else float(rich.chi2),
            "detailed_bic": None if rich is None else float(rich.bic)}


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
        return round_scores((*chi2_split(problem, none), none.n_params),
                            score_rows(problem, refits), n_data, n_modal=n_modal)[0]

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
    candidates of the next round have a location of their own), and a mass on grids that a mass
    named with one share per grid already covers
    (:func:`pipeline.diagnose.effects.distributed`: its shares are free there).

    Parameters
    ----------
    cands : sequence of Candidate, a round's library.
    effects : sequence of (Candidate, values), the effects named so far.
    """
    named = {(s.kind, s.location) for c, _ in effects for s in sites(c)}
    hung = {s.location.elements[0] for c, _ in effects for s in sites(c)
            if s.kind == "joint_flexibility"}
    shared = [set(c.location.grids) for c, _ in effects if c.get("per_grid")]
    return [c for c in cands if not any(
        (s.kind, s.location) in named
        or (s.kind == "joint_flexibility" and s.location.elements[0] in hung)
        or (s.kind == "lumped_mass" and any(set(s.location.grids) <= g for g in shared))
        for s in sites(c))]


def _say(progress, text: str) -> None:
    if progress is not None:
        progress(text)



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
    check_inputs(configurations, settings)
    refs, notes, hung = checked(configurations, settings)
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
        table, separating, first, splits = (), None, None, None
        n_hung = suspension_effects(suspension)
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
                         jacobian_theta=cal.jacobian) if effects else none_fit(problem, cal,
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
            scored = ((*chi2_split(problem, none), none.n_params), score_rows(problem, fits),
                      int(problem.modal_rows().sum()))
            alike = cache(lambda i, j: indistinguishable(problem, fits[i], fits[j]))
            verdict, best, runner, lead, reason, c = decide(
                scored[0], scored[1], settings.margin, n_data, len(cands),
                n_modal=scored[2], held_out=(modes_none, modes, entries), alike=alike,
                confirm=k > 0)
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
                if bound:
                    notes.append(bound_note(k, cand, bound, outward, gain, c, settings.margin))
                if bound and outward and gain / c > settings.margin:
                    verdict = "unexplained"
            if verdict == "effect":
                found = best_load_path(problem, theta, effects, none_evs, r0)
                verdict, path = against_path(found, problem, scored, best, n_data, len(cands),
                                              settings.margin)
                rich = (detailed(problem, effects, fits[best], n_data=n_data,
                                 jacobian_theta=cal.jacobian)
                        if verdict == "ambiguous"
                        and fits[best].candidate.kind == "joint_flexibility" else None)
                if rich is not None:
                    row = score_rows(problem, [rich])
                    again = against_path(found, problem, (scored[0], scored[1][:best] + row +
                                                           scored[1][best + 1:], scored[2]),
                                          best, n_data, len(cands), settings.margin)
                    notes.append(rich_path_note(k, fits[best], rich, path, again))
                    if again[0] == "effect":
                        verdict, path = again
                        fits[best] = rich
                        modes[best] = held_out_modes(problem, rich.evaluations)[0]
            spread, note = (sites_elsewhere(
                problem, r0, rows, fits, best, none, n_data, len(cands), settings.margin, near,
                lambda j: alike(best, j) or held_out_evidence(modes_none, modes[j], entries, c)
                < -settings.margin) if verdict == "effect" else ((), None))
            rounds.append(round_record(k, verdict, fits, best, runner, none,
                                        (modes_none, modes, entries), n_data, scored + (c,),
                                        path, same, reason=reason, margin=settings.margin,
                                        elsewhere_sites=spread))
            if note:
                notes.append(f"round {k + 1}: {note}")
            if path is not None and verdict in ("unexplained", "ambiguous"):
                notes.append(load_path_note(k, fits[best].candidate, path, verdict))
            if reason == "held_out":
                notes.append(held_out_veto_note(k, fits[best].candidate, none, fits[best],
                                                modes_none, modes[best], rounds[-1]["best"]))
            if reason == "unconfirmed":
                notes.append(unconfirmed_note(k, fits[best].candidate, lead,
                                              rounds[-1]["best"]["held_out_evidence"],
                                              settings.margin))
            if reason == "past_veto" and verdict == "effect":
                notes.append(past_veto_note(k, fits[best].candidate, rounds[-1]["vetoed"], lead,
                                            rounds[-1]["best"]["held_out_evidence"]))
            if reason == "held_out_reversal":
                notes.append(reversal_note(k, fits, best, runner, lead, scored, n_data,
                                           len(cands), (modes_none, modes, entries), c,
                                           verdict))
            if k == 0:
                first = verdict
                table = ranking_table(problem, r0, rows, fits, none, n_data, len(cands))
            if verdict == "ambiguous" and not effects:
                separating = (load_path_measurement(fits[best].candidate, path[0])
                              if path is not None else
                              separating_measurement(problem, fits[best], fits[runner]))
            if verdict != "effect":
                break
            tried = located(problem, effects, fits[best], rows, fits, near, n_data=n_data,
                            jacobian_theta=cal.jacobian)
            fit, rich = min(tried, key=lambda pair: (pair[1] or pair[0]).bic)
            if len(tried) > 1:
                rounds[-1]["neighbours"] = [_form_record(f, r) for f, r in tried]
                notes.append(located_note(k, tried, fit))
            chosen = fit
            if rich is not None:
                notes.append(f"round {k + 1}: {chosen.candidate.kind} {chosen.candidate.label} "
                             f"added {form_text(rich.candidate)}: chi^2 "
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
            _say(progress, f"round {k + 1}: refitting on the other splits of the modes")
            if splits is None:
                splits = open_splits(problem, settings.holdout, effects[:n_hung]) or ()
            extended = [extend(s, chosen.candidate, chosen.values, c) for s in splits]
            if splits and None not in extended:
                supports = [e[1] for e in extended]
                rounds[-1]["splits"] = support_records(chosen.candidate, supports)
                if not stable(supports, settings.holdout):
                    rounds[-1].update(verdict="unexplained", reason="unstable")
                    first = "unexplained" if k == 0 else first
                    notes.append(stability_note(k, chosen.candidate, supports, settings.holdout))
                    break
                splits = tuple(e[0] for e in extended)
            else:
                splits = ()
            gap_after = rounds[-1]["gap"] = gap_metrics(problem, chosen.evaluations)
            rounds[-1]["nominal"] = {n: float(t) for n, t in zip(problem.names, chosen.theta)}
            errors = standard_errors(problem, effects, chosen, c, jacobian_theta=cal.jacobian)
            if note := undetermined_note(k, chosen.candidate, chosen.values, errors):
                notes.append(note)
            records.append(EffectRecord(chosen.candidate, chosen.values, lead, spread, errors))
            effects.append((chosen.candidate, chosen.values))
            theta, none_evs = chosen.theta, chosen.evaluations
    verdict = "effect" if len(records) > n_hung else first      # the structure's, not the test's
    if records and (note := held_out_note(gap_before, gap_after)):
        notes.append(note)
    if records and (note := offdiag_note(problem, cal.evaluations, none_evs)):
        notes.append(note)
    if records and splits is None:
        _say(progress, "cross-validating the gap")
        with threadpool_limits(limits=1):
            splits = open_splits(problem, settings.holdout, effects[:n_hung]) or ()
    if records and not splits:
        notes.append("gap: not cross-validated: a refit on another split of the modes could "
                     "not be analysed at its start.")
    elif records:
        cv = cross_validated(gap_before, gap_after, splits)
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

