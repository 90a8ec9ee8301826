"""A look-again round's scores and records (:func:`pipeline.diagnose.diagnose`, steps 4-5).

The scores of refitted candidates as :func:`pipeline.diagnose.verdict.decide` takes them
(:func:`chi2_split`, :func:`score_rows`), the "none" fit of a round (:func:`none_fit`), the
named effect set against the best load path (:func:`against_path`), every screened candidate
ranked (:func:`ranked`: the first round's :func:`ranking_table`, the JSON ``candidates``, and
the sites of the named kind that make its site uncertain, :func:`sites_elsewhere`) and each
round's JSON record (:func:`round_record`, the JSON ``rounds``).
"""
from __future__ import annotations

import numpy as np

from pipeline.diagnose.calibrate import Problem
from pipeline.diagnose.fit_statistics import bic, chi_square
from pipeline.diagnose.gap import separating_measurement
from pipeline.diagnose.loadpath import outscores
from pipeline.diagnose.predictive import held_out_evidence, kept_modes
from pipeline.diagnose.result import CandidateScore, location_dict
from pipeline.diagnose.refit import Refitted
from pipeline.diagnose.verdict import elsewhere, round_scores

#: Sites of an uncertain site's note listed by name (the JSON lists all).
SHOWN = 6


def chi2_split(problem: Problem, fit) -> tuple:
    """(chi2_modal, chi2_stated) of a refit: its training residual's modal rows and the rest
    (:meth:`pipeline.diagnose.calibrate.Problem.modal_rows`); they sum to ``fit.chi2``."""
    r, modal = problem.residual(fit.theta, fit.evaluations), problem.modal_rows()
    return chi_square(r[modal]), chi_square(r[~modal])


def score_rows(problem: Problem, refits) -> list:
    """The (kind, location, chi2_modal, chi2_stated, n_params) rows of refitted candidates that
    :func:`pipeline.diagnose.verdict.decide` and
    :func:`~pipeline.diagnose.verdict.round_scores` take."""
    return [(f.candidate.kind, f.candidate.location, *chi2_split(problem, f), f.n_params)
            for f in refits]


def ranked(problem: Problem, r0, rows, refits, none, n_data: int, n_candidates: int) -> list:
    """(score, candidate or None for "none", refitted) of every screened candidate and "none",
    best first, by the scores :func:`pipeline.diagnose.verdict.decide` compared
    (:func:`~pipeline.diagnose.verdict.round_scores`: refitted ones from their refit, the rest
    from their linearised residual r0 + S x (:class:`pipeline.diagnose.screen.Screened`: S x is
    the residual's change at x for every kind) with the same modal dispersion c, "none" with its
    prior odds)."""
    modal = problem.modal_rows()
    scores, none_score, c = round_scores((*chi2_split(problem, none), none.n_params),
                                         score_rows(problem, refits), n_data, n_candidates,
                                         n_modal=int(modal.sum()))
    scored = [(float(b), fit.candidate, True) for b, fit in zip(scores, refits)]
    done = {id(fit.candidate) for fit in refits}
    for row in rows:
        if id(row.candidate) not in done:
            p = len(row.candidate.parameters) + problem.n_theta
            r = r0 + row.signature @ row.values                              # linearised residual
            scored.append((chi_square(r[modal]) / c + chi_square(r[~modal]) + p * np.log(n_data),
                           row.candidate, False))
    scored.append((none_score, None, True))
    return sorted(scored, key=lambda s: s[0])


def ranking_table(problem: Problem, r0, rows, refits, none, n_data: int,
                  n_candidates: int) -> tuple:
    """The first round's ranked candidates (:func:`ranked`), scores minus the best's."""
    scored = ranked(problem, r0, rows, refits, none, n_data, n_candidates)
    best = scored[0][0]
    return tuple(CandidateScore(c.kind if c else "none", location_dict(c.location if c else None),
                                float(b - best), c.label if c else "nothing missing", refitted)
                 for b, c, refitted in scored)


def none_fit(problem: Problem, cal, n_data: int):
    return Refitted(None, np.zeros(0), cal.theta, cal.chi2, bic(cal.chi2, len(cal.theta), n_data),
                    len(cal.theta), cal.evaluations)


def against_path(found, problem: Problem, scored, best: int, n_data: int, n_candidates: int,
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


def round_record(k: int, verdict: str, fits, best, runner, none, held_out, n_data: int,
                  scored, path=None, alike=(), *, reason: str = "", margin: float = np.inf,
                  elsewhere_sites=()) -> dict:
    """The JSON record of round k (:class:`pipeline.diagnose.result.DiagnoseResult` ``rounds``).

    ``held_out`` is (modes_none, per fit modes, entries) of
    :func:`pipeline.diagnose.predictive.held_out_modes`; ``scored`` is (the "none" row, the fits'
    rows, n_modal, c) that :func:`pipeline.diagnose.verdict.decide` took and returned (rows
    (..., chi2_modal, chi2_stated, n_params), c the modal dispersion); ``path`` is
    (LoadPath, its score, the named effect's score) of :func:`against_path`, or None when
    the round named nothing; ``alike`` the labels of the fits that predict the same data as the
    best (:func:`pipeline.diagnose.gap.indistinguishable`); ``reason`` as
    :func:`pipeline.diagnose.verdict.decide` gave it; ``vetoed`` lists the fits whose held-out
    evidence is below -``margin``; ``elsewhere_sites`` are the named effect's uncertain sites
    (:func:`sites_elsewhere`), its ``elsewhere``.
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
            "gap": None, "nominal": None, "detailed": None, "neighbours": None,
            "best": entry(best),
            "runner_up": entry(runner),
            "alike": list(alike),
            "elsewhere": list(elsewhere_sites),
            "fits": fitted,
            "load_path": None if path is None else {
                "grids": list(path[0].grids), "stiffness": path[0].stiffness,
                "chi2": chi_square(path[0].residual), "n_pairs": path[0].n_pairs,
                "score": path[1], "named_score": path[2]}}


def sites_elsewhere(problem: Problem, r0, rows, fits, best: int, none, n_data: int,
                    n_candidates: int, margin: float, near, set_aside) -> tuple:
    """The candidates of the named fit's kind at other sites that score within the margin of it
    (:func:`pipeline.diagnose.verdict.elsewhere`: the data name the kind, not the site) and a
    note saying so.

    Every screened candidate is judged (:func:`ranked`: the refitted ones by their refit, the
    rest by their linearised fit), so that the list shows how far the site is uncertain, not
    only the few refitted.

    Parameters
    ----------
    problem : Problem
    r0, rows : the round's residual and screening (:func:`ranked`).
    fits : sequence of Refitted, the round's refits; ``best`` the named one.
    none : Refitted, the model without a further effect.
    n_data, n_candidates : int, as for :func:`pipeline.diagnose.verdict.round_scores`.
    margin : float
    near : callable(location_a, location_b) -> bool, True when b is a's neighbour.
    set_aside : callable(j) -> bool, True when refit j is no other site to list: it predicts
        the named fit's data (the same explanation) or the held-out modes contradict it (a
        compensation, not an alternative).

    Returns
    -------
    sites : tuple of dict, {"kind", "label", "location", "score", "refitted"} of each, best
        first; ``score`` its score minus the named fit's (below ``margin``).
    note : str or None, what that means for the verdict, with the measurement that would
        separate the closest refitted one from the named fit
        (:func:`pipeline.diagnose.gap.separating_measurement`); None without them.
    """
    scored = ranked(problem, r0, rows, fits, none, n_data, n_candidates)
    named = fits[best].candidate
    refitted = {id(f.candidate): i for i, f in enumerate(fits)}
    at = next(i for i, (_, c, _) in enumerate(scored) if c is named)
    close = elsewhere([(c.kind if c else "none", c.location if c else None, b)
                       for b, c, _ in scored], at, margin, near,
                      lambda j: id(scored[j][1]) in refitted
                      and set_aside(refitted[id(scored[j][1])]))
    sites = tuple({"kind": scored[j][1].kind, "label": scored[j][1].label,
                   "location": location_dict(scored[j][1].location),
                   "score": float(scored[j][0] - scored[at][0]), "refitted": scored[j][2]}
                  for j in close)
    if not sites:
        return sites, None
    shown = ", ".join(f"{e['label']} (+{e['score']:.1f})" for e in sites[:SHOWN])
    more = f" and {len(sites) - SHOWN} more" if len(sites) > SHOWN else ""
    rival = next((refitted[id(scored[j][1])] for j in close if scored[j][2]), None)
    return sites, (f"{named.kind} {named.label} beats every other kind and 'none' by the margin "
                   f"{margin:g} but not its own kind at {shown}{more}: the kind is named, its "
                   "site uncertain"
                   + ("" if rival is None else
                      "; " + separating_measurement(problem, fits[best], fits[rival])))
