"""pipeline.diagnose.outputs: the text summary of a diagnosis' JSON record."""
from __future__ import annotations

from pipeline.diagnose.outputs import verdict_summary

RECORD = {
    "verdict": "effect",
    "effects": [{"kind": "boundary_stiffness",
                 "location": {"grids": [204], "elements": [], "properties": []},
                 "parameters": {"k_z": 0.111}, "quantities": {"K3": 64.0},
                 "label": "grid 204 z", "score": 73.0,
                 "elsewhere": [{"kind": "boundary_stiffness", "label": "grid 148 z",
                                "location": {"grids": [148]}, "score": 0.2185},
                               {"kind": "boundary_stiffness", "label": "grid 205 z",
                                "location": {"grids": [205]}, "score": 0.5468}]}],
    "candidates": [],
    "gap_before": {"frequency_rms_held_out": 1.2},
    "gap_after": {"frequency_rms_held_out": 1.0},
    "notes": [],
}


def test_an_uncertain_site_is_listed_under_its_effect():
    lines = verdict_summary(RECORD).splitlines()
    assert lines[:4] == [
        "verdict: effect",
        "  effect 1: boundary_stiffness at grids [204]: k_z = 0.111",
        "    adds (deck units): K3 = 64",
        "    site uncertain, also fits within the margin: grid 148 z (+0.2); grid 205 z (+0.5)"]
    certain = {**RECORD, "effects": [{**RECORD["effects"][0], "elsewhere": []}]}
    assert not any("site uncertain" in line for line in verdict_summary(certain).splitlines())


def test_standard_errors_beside_the_parameters():
    """Each parameter with its standard error, "not determined" where it is null; without
    ``standard_errors`` (a suspension, an older record) the values alone."""
    joint = {**RECORD["effects"][0], "kind": "joint_flexibility", "elsewhere": [],
             "parameters": {"compliance_x": 1472.83, "compliance_rx": 320.92},
             "standard_errors": {"compliance_x": 6.553, "compliance_rx": None}}
    line = verdict_summary({**RECORD, "effects": [joint]}).splitlines()[1]
    assert line.endswith("compliance_x = 1473 +- 6.6, compliance_rx = 320.9 (not determined)")
