"""The cross-validated gap: every paired mode judged by a fit of the named effects that did not
see it.

The workflow holds out every ``holdout``-th paired mode of each configuration
(:func:`pipeline.diagnose.evidence.holdout_mask`, rotated by the configuration's position) and
judges the named effects on those modes alone (``frequency_rms_held_out``,
:mod:`pipeline.diagnose.gap`). With one configuration that is a third of the modes, and an
effect that moves mostly training modes leaves the held-out ones within the noise, where their
change judges nothing (:func:`pipeline.diagnose.gap.held_out_note`). Frame blind study, joint
seed 1: the held-out error goes 1.26 -> 1.73 % while every paired mode goes 8.50 -> 1.31 %.

So the split is turned (k-fold cross-validation, k = ``holdout``). For every other rotation
s = 1 .. holdout - 1 (each configuration's held-out positions moved by s, :func:`rotated`):

- *before*: the nominal parameters are calibrated again on that split's training modes
  (:func:`pipeline.diagnose.calibrate.calibrate`);
- *after*: the named effects are fitted again on the same training modes, their kind and place
  kept, in the order they were named, each from its named values with the nominal parameters
  free (:func:`pipeline.diagnose.refit.continued`). A suspension identified from the suspension
  modes is kept as identified: it does not depend on the split, and only the nominal parameters
  are refitted with it.

The splits are kept through the rounds (:class:`Split`, :func:`open_splits`): when a round names
an effect, it is refitted on every other split (:func:`extend`) from its named values and kept
there when that split's training modes want it (below), and the same refits give the
cross-validated gap at the end. With the workflow's own split, every paired mode
is held out exactly once. The pooled measures go into ``gap_before`` and ``gap_after``:

- ``frequency_rms_cross_validated`` [%]: the RMS of paper eq. 18 over every split's held-out
  modes, each mode taken from its own split's fit;
- ``frequency_rms_cross_validated_expected`` [%]: the level that noise and nominal scatter alone
  give, pooled the same way from the splits' ``frequency_rms_held_out_expected``;
- ``n_cross_validated``: the number of modes pooled;
- ``max_cross_orthogonality_offdiag_cross_validated``: the largest of the splits'
  ``max_cross_orthogonality_offdiag_held_out``;
- ``mac_min_cross_validated``: the smallest of the splits' ``mac_min_held_out``.

What this judges, and what it does not. It judges the effects' *parameters*, fitted without the
mode being judged, and whether each split's training modes want the effect at all: a split
whose score does not improve with it (gain <= 0, below) goes on without it, as the workflow
would not have named it there (cross-validation repeats every step of the procedure it judges
that uses the data, the choice between the effect and no effect included; Hastie, Tibshirani &
Friedman 2009 sec. 7.10.2). It does not judge their *kind and place*: those were named on the
first split's training modes, and those include the other splits' held-out modes. For a correctly
named effect (the blind study's criterion) the choice is right by construction. There the
cross-validated gap measures what adding the effect does to modes no fit of it saw, on
``holdout`` times the modes of the first split. That matters because the relative spread of an
RMS over n modes is about 1 / sqrt(2 n).

Stability of a name. The same refits say whether a name rests on which modes were held out.
Refitted on another split's training modes, the named effect either still earns its parameters
there (its score, chi2_modal / c + chi2_stated + p ln n with the round's dispersion c as
:func:`pipeline.diagnose.verdict.round_scores` has it, lower than without it) or it does not
(its parameters fall back toward "no effect", or it fits no better than the model without it).
A name is kept when a majority of the ``holdout`` splits support it, the naming split one of
them (:func:`stable`; stability selection: keep what is selected on most subsamples of the data,
Meinshausen & Buhlmann 2010, who put the threshold between 0.6 and 0.9 of them). The wing box's
soft-panel seed 1 (an effect outside the library): a lumped mass at the tip fitted the naming
split's training modes (chi^2 1946 -> 1381, c = 13.8) and the other two splits refitted it to
zero mass (gain -9.5 each: the two parameters' 2 ln 115): named on one split of three.
"""
from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import numpy as np

from pipeline.diagnose.calibrate import Calibration, Problem, calibrate
from pipeline.diagnose.evidence import holdout_mask, with_training
from pipeline.diagnose.fit_statistics import chi_square
from pipeline.diagnose.gap import gap_metrics
from pipeline.diagnose.predictive import held_out_evidence, held_out_modes
from pipeline.diagnose.refit import continued, refit


class Split(NamedTuple):
    """Another split of the paired modes (rotation ``shift``) with the effects named so far
    refitted on its training modes, in the order they were named (the suspension first).

    ``gap_before``: :func:`pipeline.diagnose.gap.gap_metrics` of its calibration;
    ``theta``, ``evaluations``: its model with ``effects`` (Candidate, values)."""

    shift: int
    problem: Problem
    cal: Calibration
    gap_before: dict
    effects: tuple
    theta: np.ndarray
    evaluations: tuple


class Support(NamedTuple):
    """A named effect refitted on another split: ``gain`` is the split's score without it minus
    with it (module docstring; > 0: the split supports it), ``values`` its refitted parameters,
    ``evidence`` the split's held-out modes for it against the split's model without it
    (:func:`pipeline.diagnose.predictive.held_out_evidence` with the naming round's c)."""

    shift: int
    gain: float
    values: np.ndarray
    evidence: float


def rotated(problem: Problem, holdout: int, shift: int) -> Problem:
    """``problem`` with every configuration's held-out modes moved by ``shift``: configuration i
    holds out :func:`pipeline.diagnose.evidence.holdout_mask` (n_test, holdout, i + shift), as
    the workflow's preflight holds out rotation i."""
    refs = tuple(with_training(ref, ~holdout_mask(ref.test_frequency.size, holdout, i + shift))
                 for i, ref in enumerate(problem.refs))
    return replace(problem, refs=refs)


def open_splits(problem: Problem, holdout: int, suspension) -> tuple | None:
    """The other splits (shifts 1 .. holdout - 1), each calibrated on its training modes and
    with the identified ``suspension`` (sequence of (Candidate, values), kept as identified:
    only the nominal parameters are refitted with it); None when a refit cannot be analysed at
    its start."""
    splits = []
    for shift in range(1, holdout):
        split = rotated(problem, holdout, shift)
        cal = calibrate(split)
        theta, evaluations = cal.theta, cal.evaluations
        if suspension:
            hung = refit(split, theta, list(suspension), None, n_data=cal.n_data,
                         jacobian_theta=cal.jacobian)
            if hung is None:
                return None
            theta, evaluations = hung.theta, hung.evaluations
        splits.append(Split(shift, split, cal, gap_metrics(split, cal.evaluations),
                            tuple(suspension), theta, evaluations))
    return tuple(splits)


def _score(problem: Problem, theta, evaluations, c: float) -> float:
    """chi2_modal / c + chi2_stated of a model on the problem's training rows."""
    r, modal = problem.residual(theta, evaluations), problem.modal_rows()
    return chi_square(r[modal]) / c + chi_square(r[~modal])


def extend(split: Split, candidate, values, c: float) -> tuple | None:
    """A named effect added on another split: its fit continued from its named ``values`` with
    the nominal parameters free (:func:`pipeline.diagnose.refit.continued`).

    Parameters
    ----------
    split : Split
    candidate : Candidate, the named effect.
    values : (npar,) its named parameters (the start).
    c : float, the naming round's modal dispersion.

    Returns
    -------
    (Split, Support) : the split with the effect where it supports it (gain > 0), else the split
    as it was (module docstring), and the split's support for it; None when the refit cannot be
    analysed at its start.
    """
    p, cal = split.problem, split.cal
    fit = continued(p, split.theta, list(split.effects), candidate, values, n_data=cal.n_data,
                    jacobian_theta=cal.jacobian)
    if fit is None:
        return None
    gain = (_score(p, split.theta, split.evaluations, c) - _score(p, fit.theta, fit.evaluations, c)
            - len(candidate.parameters) * np.log(cal.n_data))
    none_modes, entries = held_out_modes(p, split.evaluations)
    evidence = held_out_evidence(none_modes, held_out_modes(p, fit.evaluations)[0], entries, c)
    support = Support(split.shift, float(gain), np.asarray(fit.values, float), evidence)
    if gain <= 0.0:
        return split, support
    return (split._replace(effects=split.effects + ((candidate, fit.values),), theta=fit.theta,
                           evaluations=fit.evaluations), support)


def supporting(supports) -> int:
    """The splits that support a named effect: the naming split and the others whose gain is
    > 0."""
    return 1 + sum(s.gain > 0.0 for s in supports)


def stable(supports, holdout: int) -> bool:
    """True when the splits :func:`supporting` the effect are more than half of the ``holdout``
    splits (module docstring)."""
    return supporting(supports) > holdout / 2.0


def support_records(candidate, supports) -> list:
    """The round record's ``splits``: per other split its ``shift``, ``gain``,
    ``held_out_evidence`` and refitted ``parameters`` of ``candidate``."""
    return [{"shift": s.shift, "gain": s.gain, "held_out_evidence": s.evidence,
             "parameters": dict(zip(candidate.parameters, map(float, s.values)))}
            for s in supports]


def stability_note(k: int, candidate, supports, holdout: int) -> str:
    """The note of an effect a round named on its own split that most splits do not support."""
    gains = ", ".join(f"{s.gain:+.1f}" for s in supports)
    n = supporting(supports)
    return (f"round {k + 1}: {candidate.kind} {candidate.label} fits this split's training modes "
            f"best, but refitted on the other splits of the paired modes (each holding out a "
            f"different one in {holdout} of them) it gains {gains} in score (> 0: that split "
            f"supports it): supported on {n} of {holdout} splits. A name that rests on which "
            "modes are held out is not named; the round is unexplained.")


def pooled(gaps) -> dict:
    """The cross-validated measures (module docstring) of the splits' gaps.

    Parameters
    ----------
    gaps : sequence of dict of :func:`pipeline.diagnose.gap.gap_metrics`, one per split.

    Returns
    -------
    dict with the ``*_cross_validated`` keys (None where no split has held-out modes or
    shapes).
    """
    held = [g for g in gaps if g["n_held_out"]]
    n = np.array([g["n_held_out"] for g in held], float)

    def rms(key):
        if not held:
            return None
        return float(np.sqrt(np.sum(n * np.array([g[key] for g in held]) ** 2) / n.sum()))

    cross = [g["max_cross_orthogonality_offdiag_held_out"] for g in held
             if g["max_cross_orthogonality_offdiag_held_out"] is not None]
    macs = [g["mac_min_held_out"] for g in held if g["mac_min_held_out"] is not None]
    return {"frequency_rms_cross_validated": rms("frequency_rms_held_out"),
            "frequency_rms_cross_validated_expected": rms("frequency_rms_held_out_expected"),
            "n_cross_validated": int(n.sum()),
            "max_cross_orthogonality_offdiag_cross_validated": max(cross) if cross else None,
            "mac_min_cross_validated": min(macs) if macs else None}


def cross_validated_note(gap_before: dict, gap_after: dict, holdout: int) -> str:
    """The note of the cross-validated gap (module docstring) before -> after."""
    b, a = gap_before, gap_after
    text = (f"gap, cross-validated over {holdout} splits of the paired modes (each held out "
            f"once; per split the calibration and the named effects refitted, kind and place "
            f"kept, on its training modes): RMS frequency error "
            f"{b['frequency_rms_cross_validated']:.2f} -> {a['frequency_rms_cross_validated']:.2f}"
            f" % over {a['n_cross_validated']} modes (noise and nominal scatter alone give about "
            f"{a['frequency_rms_cross_validated_expected']:.2f} %)")
    if a["max_cross_orthogonality_offdiag_cross_validated"] is not None:
        text += (f"; largest held-out cross-orthogonality off-diagonal "
                 f"{b['max_cross_orthogonality_offdiag_cross_validated']:.3f} -> "
                 f"{a['max_cross_orthogonality_offdiag_cross_validated']:.3f}")
    return text + "."


def cross_validated(gap_before: dict, gap_after: dict, splits) -> tuple:
    """The cross-validated gap before and after (module docstring).

    Parameters
    ----------
    gap_before, gap_after : dict, the workflow's gaps on its own split.
    splits : sequence of Split, the other splits with every named effect added.

    Returns
    -------
    (dict, dict) of :func:`pooled` before and after.
    """
    return (pooled([gap_before] + [s.gap_before for s in splits]),
            pooled([gap_after] + [gap_metrics(s.problem, s.evaluations) for s in splits]))
