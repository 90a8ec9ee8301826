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
  free (:func:`pipeline.diagnose.screen.continued`). A suspension identified from the suspension
  modes is kept as identified: it does not depend on the split, and only the nominal parameters
  are refitted with it.

With the workflow's own split, every paired mode is held out exactly once. The pooled measures
go into ``gap_before`` and ``gap_after``:

- ``frequency_rms_cross_validated`` [%]: the RMS of paper eq. 18 over every split's held-out
  modes, each mode taken from its own split's fit;
- ``frequency_rms_cross_validated_expected`` [%]: the level that noise and nominal scatter alone
  give, pooled the same way from the splits' ``frequency_rms_held_out_expected``;
- ``n_cross_validated``: the number of modes pooled;
- ``max_cross_orthogonality_offdiag_cross_validated``: the largest of the splits'
  ``max_cross_orthogonality_offdiag_held_out``;
- ``mac_min_cross_validated``: the smallest of the splits' ``mac_min_held_out``.

What this judges, and what it does not. It judges the effects' *parameters*, fitted without the
mode being judged. It does not judge their *choice*: the kind and place were named on the first
split's training modes, and those include the other splits' held-out modes. For a correctly
named effect (the blind study's criterion) the choice is right by construction. There the
cross-validated gap measures what adding the effect does to modes no fit of it saw, on
``holdout`` times the modes of the first split. That matters because the relative spread of an
RMS over n modes is about 1 / sqrt(2 n).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from pipeline.diagnose.calibrate import Problem, calibrate
from pipeline.diagnose.evidence import holdout_mask, with_training
from pipeline.diagnose.gap import gap_metrics
from pipeline.diagnose.screen import continued, refit


def rotated(problem: Problem, holdout: int, shift: int) -> Problem:
    """``problem`` with every configuration's held-out modes moved by ``shift``: configuration i
    holds out :func:`pipeline.diagnose.evidence.holdout_mask` (n_test, holdout, i + shift), as
    the workflow's preflight holds out rotation i."""
    refs = tuple(with_training(ref, ~holdout_mask(ref.test_frequency.size, holdout, i + shift))
                 for i, ref in enumerate(problem.refs))
    return replace(problem, refs=refs)


def split_gaps(problem: Problem, suspension, named) -> tuple | None:
    """The gap before and after on one split (module docstring).

    Parameters
    ----------
    problem : Problem, the split (:func:`rotated`).
    suspension : sequence of (Candidate, values), the identified suspension (kept as it is).
    named : sequence of (Candidate, values), the named effects in the order they were named
        (the start of each refit).

    Returns
    -------
    (dict, dict) of :func:`pipeline.diagnose.gap.gap_metrics`, or None when a refit cannot be
    analysed at its start.
    """
    cal = calibrate(problem)
    before = gap_metrics(problem, cal.evaluations)
    effects, theta, evaluations = list(suspension), cal.theta, cal.evaluations
    if effects:
        hung = refit(problem, theta, effects, None, n_data=cal.n_data,
                     jacobian_theta=cal.jacobian)
        if hung is None:
            return None
        theta, evaluations = hung.theta, hung.evaluations
    for candidate, values in named:
        fit = continued(problem, theta, effects, candidate, values, n_data=cal.n_data,
                        jacobian_theta=cal.jacobian)
        if fit is None:
            return None
        effects.append((candidate, fit.values))
        theta, evaluations = fit.theta, fit.evaluations
    return before, gap_metrics(problem, evaluations)


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


def cross_validated(problem: Problem, holdout: int, gap_before: dict, gap_after: dict,
                    suspension, named) -> tuple | None:
    """The cross-validated gap before and after (module docstring).

    Parameters
    ----------
    problem : Problem, the workflow's split (rotation 0).
    holdout : int, the workflow's ``holdout``.
    gap_before, gap_after : dict, the workflow's gaps on its own split.
    suspension, named : as in :func:`split_gaps`.

    Returns
    -------
    (dict, dict) of :func:`pooled` before and after, or None when a split's refit fails.
    """
    before, after = [gap_before], [gap_after]
    for shift in range(1, holdout):
        gaps = split_gaps(rotated(problem, holdout, shift), suspension, named)
        if gaps is None:
            return None
        before.append(gaps[0])
        after.append(gaps[1])
    return pooled(before), pooled(after)
