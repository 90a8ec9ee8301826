"""pipeline.diagnose.plots: the candidate ranking and the gap figures, drawn from a JSON record of
the contract's schema, on Figures without pyplot state."""
from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure

from pipeline.diagnose.plots import KIND_COLOURS, candidate_label, plot_candidates, plot_gap

RECORD = {
    "verdict": "effect",
    "effect": {"kind": "joint_flexibility",
               "location": {"grids": [5011, 5021], "elements": [5100], "properties": []},
               "parameters": {"compliance": 3.2}},
    "candidates": [
        {"kind": "joint_flexibility", "location": {"grids": [5011], "elements": [5100],
                                                   "properties": []},
         "score": 0.0, "label": "RBE2 5100 (engine 5011-5021)"},
        {"kind": "lumped_mass", "location": {"grids": [3005], "elements": [], "properties": []},
         "score": 14.5},
        {"kind": "member_taper", "location": {"grids": [], "elements": [], "properties": [151]},
         "score": 40.25, "label": "PBAR 151"},
    ],
    "gap_before": {"frequency_rms_held_out": 4.1, "frequency_rms": 3.9,
                   "frequency_rms_cross_validated": 3.5,
                   "max_cross_orthogonality_offdiag": 0.31, "mac_min": 0.62,
                   "mass": {"weight": -3.5, "x_cg": 1.0}, "flutter_speed": 1200.0},
    "gap_after": {"frequency_rms_held_out": 0.8, "frequency_rms": 0.7,
                  "frequency_rms_cross_validated": 0.75,
                  "max_cross_orthogonality_offdiag": 0.05, "mac_min": 0.97,
                  "mass": {"weight": -0.2, "x_cg": 0.1}, "flutter_speed": 1100.0},
    "notes": [],
}


def test_candidates_are_bars_of_their_score_coloured_by_kind():
    open_before = plt.get_fignums()
    fig = plot_candidates(RECORD)
    assert isinstance(fig, Figure) and plt.get_fignums() == open_before   # no pyplot figure
    ax = fig.axes[0]
    bars = sorted(ax.patches, key=lambda p: -p.get_y())     # best at the top
    np.testing.assert_allclose([b.get_width() for b in bars], [0.0, 14.5, 40.25], atol=0.0)
    assert [b.get_facecolor() for b in bars] == [to_rgba(KIND_COLOURS[k]) for k in
                                                 ("joint_flexibility", "lumped_mass",
                                                  "member_taper")]
    labels = [t.get_text() for t in sorted(ax.get_yticklabels(), key=lambda t: -t.get_position()[1])]
    assert labels == ["RBE2 5100 (engine 5011-5021)", "lumped_mass (grids [3005])", "PBAR 151"]
    assert sorted(t.get_text() for t in ax.get_legend().get_texts()) == sorted(
        ("joint_flexibility", "lumped_mass", "member_taper"))


def test_candidates_top_then_the_best_of_every_other_kind():
    """The best ``top``, then (after a gap) the best of each kind not among them: with top = 1
    the mass and the taper below the joint; ``none`` is named "nothing missing"."""
    record = {**RECORD, "candidates": RECORD["candidates"] + [
        {"kind": "lumped_mass", "location": {"grids": [3006]}, "score": 50.0},
        {"kind": "none", "location": {}, "score": 60.0, "label": "nothing missing"}]}
    assert len(plot_candidates(record, top=5).axes[0].patches) == 5
    ax = plot_candidates(record, top=1).axes[0]
    bars = sorted(ax.patches, key=lambda p: -p.get_y())
    np.testing.assert_allclose([b.get_width() for b in bars], [0.0, 14.5, 40.25, 60.0])
    assert [b.get_y() for b in bars][:2] == [bars[0].get_y(), bars[0].get_y() - 2.0]  # the gap
    labels = [t.get_text() for t in sorted(ax.get_yticklabels(),
                                           key=lambda t: -t.get_position()[1])]
    assert labels == ["RBE2 5100 (engine 5011-5021)",
                      "best lumped_mass: lumped_mass (grids [3005])",
                      "best member_taper: PBAR 151", "nothing missing"]


def test_candidates_empty():
    empty = plot_candidates({"verdict": "none", "candidates": []})
    assert [t.get_text() for t in empty.axes[0].texts] == ["no candidate screened"]
    assert candidate_label({"kind": "none", "location": {}}) == "none"


def test_gap_groups_before_and_after_per_metric():
    open_before = plt.get_fignums()
    fig = plot_gap(RECORD)
    assert isinstance(fig, Figure) and plt.get_fignums() == open_before
    assert [ax.get_title() for ax in fig.axes] == ["frequency error", "mode shapes",
                                                   "mass properties", "flutter"]
    heights = [[p.get_height() for p in ax.patches] for ax in fig.axes]
    # bars: every "before" of the panel, then every "after"
    assert heights[0] == [4.1, 3.5, 3.9, 0.8, 0.75, 0.7]
    assert heights[1] == [0.31, 0.62, 0.05, 0.97]
    assert heights[2] == [-3.5, 1.0, -0.2, 0.1]
    assert heights[3] == [1200.0, 1100.0]
    assert [t.get_text() for t in fig.legends[0].get_texts()] == ["before", "after"]
    # room beyond the longest bars for their values: mass errors -3.5 .. 1.0, pad 0.12 x 4.5
    np.testing.assert_allclose(fig.axes[2].get_ylim(), (-3.5 - 0.54, 1.0 + 0.54))
    # each bar carries its value, so that an "after" of 0 reads 0 rather than missing
    assert [t.get_text() for t in fig.axes[1].texts] == ["0.31", "0.62", "0.05", "0.97"]
    zero = {**RECORD, "gap_after": {**RECORD["gap_after"], "frequency_rms_held_out": 0.0}}
    assert [t.get_text() for t in plot_gap(zero).axes[0].texts] == ["4.1", "3.5", "3.9", "0",
                                                                   "0.75", "0.7"]


def test_gap_without_mass_or_flutter_leaves_their_panels_out():
    record = {"gap_before": {k: v for k, v in RECORD["gap_before"].items()
                             if k not in ("mass", "flutter_speed")},
              "gap_after": {**RECORD["gap_after"], "mass": {}, "flutter_speed": None}}
    fig = plot_gap(record)
    assert [ax.get_title() for ax in fig.axes] == ["frequency error", "mode shapes"]
    # no cross-validated gap (nothing was named): no bar for it
    plain = {w: {k: v for k, v in RECORD[w].items() if k != "frequency_rms_cross_validated"}
             for w in ("gap_before", "gap_after")}
    assert [p.get_height() for p in plot_gap(plain).axes[0].patches] == [4.1, 3.9, 0.8, 0.7]
    # test frequencies alone: no shape metric, no empty "mode shapes" panel
    bare = {w: {**RECORD[w], "max_cross_orthogonality_offdiag": None, "mac_min": None}
            for w in ("gap_before", "gap_after")}
    assert [ax.get_title() for ax in plot_gap(bare).axes] == ["frequency error",
                                                              "mass properties", "flutter"]
