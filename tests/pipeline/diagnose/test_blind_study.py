"""The blind study of ``pipeline diagnose`` (issue 14, "Must show").

* scoring rules on hand-written verdicts (no workflow run);
* quick subset (default suite, ~50 s): the frame, one seed, the kinds in ``QUICK_KINDS``, one
  look-again round (``[diagnose] max_effects = 1`` in the case file): the workflow runs on each
  generated case through the case file alone and writes a verdict of the issue's schema;
* the full study (``slow``): both structures, every truth kind, seeds 0-9, against the issue's
  thresholds -- top-1 kind accuracy >= 90 %, location (named element / grid or its neighbour)
  >= 80 % of the correctly named cases, no effect named on ``none`` data in >= 95 % of seeds,
  an effect outside the library never given a library name, and on every correctly named case
  the held-out RMS frequency error and the largest cross-orthogonality off-diagonal both drop.
  ``python -m tests.pipeline.diagnose.truth.study`` runs the same study and prints the matrix.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from tests.pipeline.diagnose.truth import KINDS, STRUCTURES, TRUTH_KINDS
from tests.pipeline.diagnose.truth.study import confusion_text, run_study, score, study_dataset

VERDICTS = ("effect", "none", "ambiguous", "unexplained")
#: The quick subset's kinds (one library kind of each family, no effect, outside the library).
QUICK_KINDS = ("lumped_mass", "member_taper", "none", "outside")
TRUTH = {"kind": "member_taper", "grids": [2002, 2003], "elements": [2003], "properties": [22],
         "neighbours": {"grids": [2001, 2002, 2003, 2004, 2102, 2103, 2202, 2203],
                        "elements": [2002, 2003, 2004, 7002, 7003]}}


def _verdict(kind, grids=(), elements=(), properties=(), verdict="effect", before=5.0,
             after=1.0):
    effect = {"kind": kind, "location": {"grids": list(grids), "elements": list(elements),
                                         "properties": list(properties)}, "parameters": {}}
    return {"verdict": verdict, "effect": effect if verdict == "effect" else None,
            "gap_before": {"frequency_rms_held_out": before,
                           "max_cross_orthogonality_offdiag": 0.3},
            "gap_after": {"frequency_rms_held_out": after,
                          "max_cross_orthogonality_offdiag": 0.1}}


def test_score_location_by_neighbour():
    neighbour = score(TRUTH, _verdict("member_taper", elements=[2004]))       # next element
    assert neighbour["kind_correct"] and neighbour["location_hit"]
    far = score(TRUTH, _verdict("member_taper", elements=[2009], grids=[2009, 2010]))
    assert far["kind_correct"] and not far["location_hit"]
    wrong = score(TRUTH, _verdict("lumped_mass", grids=[2003]))
    assert wrong["named"] == "lumped_mass" and not wrong["kind_correct"]
    assert not wrong["location_hit"]
    ambiguous = score(TRUTH, _verdict("member_taper", elements=[2003], verdict="ambiguous"))
    assert ambiguous["named"] == "ambiguous" and not ambiguous["location_hit"]


def test_scores_of_a_study():
    rows = [{"structure": "frame", "truth_kind": kind, "seed": 0, "seconds": 1.0, "error": "",
             **score({**TRUTH, "kind": kind}, result)}
            for kind, result in (("member_taper", _verdict("member_taper", elements=[2003])),
                                 ("member_taper", _verdict("member_curvature", elements=[2003])),
                                 ("none", _verdict("none", verdict="none")),
                                 ("outside", _verdict("none", verdict="unexplained")),
                                 ("outside", _verdict("lumped_mass", grids=[1])))]
    ds = study_dataset(rows)
    assert ds.attrs["top1_kind_accuracy"] == 0.5
    assert ds.attrs["location_accuracy"] == 1.0
    assert ds.attrs["none_kept"] == 1.0
    assert ds.attrs["outside_not_named"] == 0.5
    assert ds.attrs["gap_shrinks"] == 1.0
    assert ds["confusion"].sel(truth_kind_row="member_taper").sum() == 2
    assert int(ds["confusion"].sel(truth_kind_row="outside",
                                   named_kind_column="unexplained")) == 1
    assert "top1_kind_accuracy: 0.500" in confusion_text(ds)


def test_quick_blind_subset(tmp_path):
    ds = run_study(["frame"], QUICK_KINDS, [0], tmp_path, diagnose={"max_effects": 1},
                   progress=None)
    assert ds.sizes["case"] == len(QUICK_KINDS)
    assert ds.attrs["errors"] == 0, ds["error"].values
    for kind in QUICK_KINDS:
        result = json.loads((tmp_path / "frame" / kind / "0" / "diagnose.json").read_text())
        assert result["verdict"] in VERDICTS
        assert {"effect", "candidates", "gap_before", "gap_after"} <= set(result)
        if result["verdict"] == "effect":
            assert result["effect"]["kind"] in KINDS
    assert (tmp_path / "study.nc").is_file()


@pytest.mark.slow
def test_full_blind_study(tmp_path):
    ds = run_study(STRUCTURES, TRUTH_KINDS, range(10), tmp_path, progress=None)
    print(confusion_text(ds))
    assert ds.attrs["errors"] == 0, ds["error"].values
    assert ds.attrs["top1_kind_accuracy"] >= 0.90
    assert ds.attrs["location_accuracy"] >= 0.80
    assert ds.attrs["none_kept"] >= 0.95
    outside = ds["named_kind"].values[ds["truth_kind"].values == "outside"]
    assert not np.isin(outside, KINDS).any(), outside
    assert ds.attrs["gap_shrinks"] == 1.0
