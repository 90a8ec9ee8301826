"""What the right answer scores: the gap of a case's own truth effect added to the analysis
model, as the workflow would have it had it named the effect exactly.

The blind study's gap criterion (issue 14: for each correctly named case the held-out RMS
frequency error and the largest cross-orthogonality off-diagonal both drop) asks of a named
effect what the truth's own effect may not give: the truth differs from the analysis model by
its effect *and* by nuisance scatter of every section and mass (``effects.scatter``), which no
effect of the library removes. So, per case, the truth's effect (``truth.json``: its kind, place
and size exactly) is added to each nominal analysis deck (``effects.apply``, without the
scatter) and the workflow's own steps are repeated on it: the same references (the preflight of
the nominal case), the nominal calibration (:func:`pipeline.diagnose.calibrate.calibrate`) on
the workflow's split and on the others (:func:`pipeline.diagnose.crossval.open_splits`), the
same gap measures (:func:`pipeline.diagnose.gap.gap_metrics`,
:func:`pipeline.diagnose.crossval.pooled`). A case the named effect misses and this misses too
is a miss of the criterion on that data, not of the naming; one this passes and the named
effect misses is the workflow's.

It differs from ``truth_gap`` (:mod:`.study`): that is the truth model itself, scatter and all,
the noise floor no model reaches; this is the best the library's answer can do on the nominal
model.
"""
from __future__ import annotations

import json
import tempfile
from pathlib import Path

from . import effects

#: A case's file of its truth effect's gap (:func:`oracle_gap`).
ORACLE_GAP = "oracle_gap.json"


def truth_effect(truth: dict) -> effects.Effect:
    """The :class:`effects.Effect` a case's ``truth.json`` records."""
    return effects.Effect(kind=truth["kind"], grids=tuple(truth["grids"]),
                          elements=tuple(truth["elements"]),
                          properties=tuple(truth["properties"]), size=float(truth["size"]),
                          params=truth["parameters"])


def with_effect(deck: Path, effect: effects.Effect, folder: Path) -> Path:
    """``deck`` with ``effect`` added (no scatter), written into ``folder``."""
    from structures.common.nastran import read_pynastran

    bdf = read_pynastran(deck)
    effects.apply(bdf, effect)
    path = Path(folder) / f"oracle_{Path(deck).name}"
    bdf.write_bdf(str(path), enddata=True)
    return path


def oracle_gap(case_toml: Path, truth: dict, *, frequency_only: bool = False) -> dict:
    """The gap of the truth's effect on the nominal model (module docstring).

    Parameters
    ----------
    case_toml : path of the case (its analysis decks, GVTs and weighings).
    truth : dict, the case's ``truth.json``.
    frequency_only : bool, the test frequencies alone (as the study ran the workflow).

    Returns
    -------
    dict: :func:`pipeline.diagnose.gap.gap_metrics` of the workflow's split with the nominal
    parameters calibrated, and the pooled ``*_cross_validated`` keys over every split.
    """
    from threadpoolctl import threadpool_limits

    from pipeline.diagnose.calibrate import Problem, calibrate
    from pipeline.diagnose.crossval import open_splits, pooled
    from pipeline.diagnose.gap import gap_metrics
    from structures.bdf import read_model

    from .study import case_references

    configurations, settings, refs = case_references(case_toml, frequency_only)
    effect = truth_effect(truth)
    with tempfile.TemporaryDirectory() as tmp:
        models = [read_model(with_effect(c.deck, effect, Path(tmp))) for c in configurations]
    with threadpool_limits(limits=1):
        problem = Problem.build(refs, models, settings.model_scatter)
        cal = calibrate(problem)
        gap = gap_metrics(problem, cal.evaluations)
        splits = open_splits(problem, settings.holdout, ()) or ()
    return {**gap, **pooled([gap] + [s.gap_before for s in splits]),
            "nominal": {n: float(t) for n, t in zip(problem.names, cal.theta)}}


def add_oracle_gap(folder: Path) -> dict:
    """Write ``folder / ORACLE_GAP`` for a case already run (its ``case.toml`` and
    ``truth.json``); returns it."""
    folder = Path(folder)
    truth = json.loads((folder / "truth.json").read_text())
    gap = oracle_gap(folder / "case.toml", truth)
    (folder / ORACLE_GAP).write_text(json.dumps(gap, indent=1) + "\n")
    return gap
