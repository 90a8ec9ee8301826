"""The notes a look-again round adds to the result (:func:`pipeline.diagnose.diagnose`): why
its best fit was named, or not, in words an engineer reads in the report and the JSON ``notes``.

Each function returns one note; the numbers it quotes are those the round's verdict used
(:func:`pipeline.diagnose.verdict.decide`, :func:`pipeline.diagnose.refit.bound_release`,
:func:`pipeline.diagnose.loadpath.best_load_path`, :func:`pipeline.diagnose.detail.located`).
"""
from __future__ import annotations

import numpy as np

from pipeline.diagnose.predictive import held_out_evidence
from pipeline.diagnose.verdict import on_bound, preference, round_scores

#: A parameter smaller than this share of its reference size is at 0 (:func:`undetermined_note`).
ZERO = 1e-6


def bound_note(k: int, cand, bound, outward: bool, gain: float, c: float, margin: float) -> str:
    """A named fit with ``bound`` parameters on a non-zero bound: released along the unbounded
    Gauss-Newton step, chi^2 falls by ``gain`` (``outward``: the step leaves the range). Pressed
    (outward and gain / c above ``margin``) it is not named; else it stands."""
    if outward and gain / c > margin:
        return (f"round {k + 1}: {cand.kind} {cand.label} fits best but {', '.join(bound)} sits "
                f"on its bound and the data want more (released, chi^2 falls by {gain:.1f} "
                f"along the unbounded Gauss-Newton step, {gain / c:.1f} after the dispersion "
                f"{c:.2f}): more than the library's range of that effect; not named (a "
                "different or larger effect).")
    return (f"round {k + 1}: {cand.kind} {cand.label}: {', '.join(bound)} sits on its bound, "
            "but the data do not press against it (released, the unbounded Gauss-Newton step "
            + (f"gains {gain:.1f} in chi^2, {gain / c:.1f} after the dispersion, below the "
               f"margin {margin:g})." if outward else "moves it inward)."))


def load_path_note(k: int, cand, path, verdict: str) -> str:
    """A best fit not named because the load path ``path`` = (path fit, its score, the named
    fit's score) fits better (``unexplained``) or as well (``ambiguous``)."""
    a, b = path[0].grids
    how, end = (("better", ": the effect is outside the library.") if verdict == "unexplained"
                else ("as well, within the margin", "."))
    return (f"round {k + 1}: {cand.kind} {cand.label} is not named: a load path the library "
            f"does not hold, a spring between grids {a} and {b} (k = {path[0].stiffness:.4g}), "
            f"fits the training data {how} (score {path[1]:.1f} against {path[2]:.1f}){end}")


def rich_path_note(k: int, fit, rich, path, again) -> str:
    """A joint within the margin of a load path, refitted with one compliance per CBUSH
    component (``rich``) and scored against the path again (``again``, of
    :func:`pipeline.diagnose.rounds.against_path`)."""
    return (f"round {k + 1}: {fit.candidate.kind} {fit.candidate.label} against the load path "
            f"between grids {path[0].grids[0]} and {path[0].grids[1]} within the margin: with "
            f"one compliance per CBUSH component (chi^2 {fit.chi2:.1f} -> {rich.chi2:.1f}) it "
            f"scores {again[1][2]:.1f} against the path's {again[1][1]:.1f}"
            + (", named." if again[0] == "effect" else "."))


def held_out_veto_note(k: int, cand, none, fit, modes_none, modes, record: dict) -> str:
    """A best fit of the training modes that the held-out modes contradict (reason
    ``held_out``)."""
    kept = np.asarray(record["held_out_modes_kept"])
    return (f"round {k + 1}: {cand.kind} {cand.label} fits the training modes (chi^2 "
            f"{none.chi2:.0f} -> {fit.chi2:.0f}) but not the {int(kept.sum())} held-out modes "
            f"either model reproduces (chi^2 {modes_none[kept].sum():.0f} -> "
            f"{modes[kept].sum():.0f}, evidence {record['held_out_evidence']:.1f}; per mode in "
            "the round record): it compensates for something else; not named.")


def past_veto_note(k: int, cand, vetoed, lead: float, evidence: float) -> str:
    """The best fit the held-out modes do not contradict, named past the ``vetoed`` ones
    (reason ``past_veto``)."""
    return (f"round {k + 1}: the held-out modes contradict {'; '.join(vetoed)} (a compensation "
            f"the training modes prefer); {cand.kind} {cand.label}, the best fit they do not "
            f"contradict, beats the rest by {lead:.1f} and the held-out modes support it "
            f"(evidence {evidence:+.1f}): named. The held-out modes took part in naming it, so "
            "its gap on them is no blind check.")


def unconfirmed_note(k: int, cand, lead: float, evidence: float, margin: float) -> str:
    """A later round's best fit that beats the rest on the training modes but that the held-out
    modes do not support by the margin (reason ``unconfirmed``)."""
    return (f"round {k + 1}: {cand.kind} {cand.label} beats the rest on the training modes by "
            f"{lead:.1f} but the held-out modes do not support it by the margin {margin:g} "
            f"(evidence {evidence:+.1f}): after a named effect the remainder is mostly the "
            "nominal scatter, which a local change mimics on the modes it is fitted to, so a "
            "later round names only what the modes it did not see confirm; not named.")


def reversal_note(k: int, fits, best: int, runner, lead: float, scored, n_data: int,
                  n_candidates: int, held_out, c: float, verdict: str) -> str:
    """A round whose held-out modes reversed the training ranking (reason
    ``held_out_reversal``)."""
    scores = round_scores(scored[0], scored[1], n_data, n_candidates, n_modal=scored[2])[0]
    trained = int(np.argmin(scores))
    b, a = fits[trained].candidate, fits[best].candidate
    held = held_out_evidence(held_out[1][trained], held_out[1][best], held_out[2], c)
    text = (f"round {k + 1}: the training modes prefer {b.kind} {b.label} to {a.kind} "
            f"{a.label} by {scores[best] - scores[trained]:.1f}, the held-out modes prefer the "
            f"latter by {held:.1f} (on the modes either reproduces): together by "
            f"{preference(scores, held_out, c, trained, best):.1f}, more than the margin. ")
    if verdict != "effect":
        return text + f"{a.kind} {a.label} is not named ({verdict})."
    closest = "" if runner is None else (f" beats its rivals on all the modes by {lead:.1f} "
                                         f"({fits[runner].candidate.label} the closest):")
    return text + (f"{a.kind} {a.label}{closest} named. The held-out modes took part in naming "
                   "it, so its gap on them is no blind check.")


def located_note(k: int, tried, fit) -> str:
    """A named joint compared with its neighbours (:func:`pipeline.diagnose.detail.located`):
    ``tried`` the (fit, detailed fit or None) of each, ``fit`` the one kept."""
    named = tried[0][0].candidate
    forms = "; ".join(f"{f.candidate.label} {f.chi2:.1f}"
                      + (f" -> {r.chi2:.1f}" if r is not None else "") for f, r in tried)
    text = (f"round {k + 1}: {named.kind} {named.label} and its neighbours, each refitted and in "
            f"the form of least BIC (chi^2 with two parameters -> with one compliance per "
            f"CBUSH component): {forms}; ")
    if fit is tried[0][0]:
        return text + f"{named.label} stays."
    return text + f"{fit.candidate.label} fits best and is named instead."


def undetermined_note(k: int, cand, values, errors) -> str | None:
    """A named effect's parameters whose standard error (:mod:`pipeline.diagnose.linearised`)
    is at least the value's size: the training data do not determine them (a parameter on a
    non-zero bound is left to the bound's note, one at 0, "none of it", has no size to compare
    with); None when there are none. ``errors`` None: they could not be estimated, which the
    note says."""
    if errors is None:
        return (f"round {k + 1}: {cand.label}: its standard errors are not estimated (a model "
                "stepped from the fit cannot be analysed).")
    loose = [(name, v, e) for name, v, e, lo, hi, ref
             in zip(cand.parameters, values, errors, cand.lower, cand.upper, cand.reference)
             if not on_bound(v, lo, hi) and abs(v) > ZERO * abs(ref) and not e < abs(v)]
    if not loose:
        return None
    listed = ", ".join(f"{name} = {v:.4g} +- {e:.2g}" if np.isfinite(e) else
                       f"{name} = {v:.4g} (no bound)" for name, v, e in loose)
    return (f"round {k + 1}: {cand.kind} {cand.label}: {listed}: a standard error as large as "
            "the value, the training data do not determine "
            + ("it" if len(loose) == 1 else "them")
            + "; a mode it governs that no fit saw is predicted no better than that.")
