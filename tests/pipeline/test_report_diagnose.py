"""pipeline.report_diagnose: the report's diagnose section from a run folder's diagnose.json."""
from __future__ import annotations

import json

from pipeline.report_diagnose import diagnose_section
from structures.units import unit_labels

RECORD = {
    "verdict": "effect",
    "effect": None,
    "effects": [{"kind": "joint_flexibility",
                 "location": {"grids": [5011, 5021], "elements": [5100], "properties": []},
                 "parameters": {"compliance": 3.2}, "standard_errors": {"compliance": 0.41},
                 "quantities": {"K1": 1.5e5, "K4": 2.0e3},
                 "label": "RBE2 5100", "score": 42.0},
                {"kind": "boundary_stiffness",
                 "location": {"grids": [204], "elements": [], "properties": []},
                 "parameters": {"k_z": 0.11}, "standard_errors": {"k_z": None},
                 "quantities": {"K3": 64.0},
                 "label": "grid 204 z", "score": 73.0,
                 "elsewhere": [{"kind": "boundary_stiffness", "label": "grid 148 z",
                                "location": {"grids": [148], "elements": [], "properties": []},
                                "score": 0.2}]}],
    "candidates": [{"kind": "joint_flexibility", "label": "RBE2 5100", "score": 0.0,
                    "location": {"grids": [5011], "elements": [5100], "properties": []}},
                   {"kind": "lumped_mass", "label": "grid 3005", "score": 42.0,
                    "location": {"grids": [3005], "elements": [], "properties": []}}],
    "gap_before": {"frequency_rms_held_out": 4.1, "mac_min": 0.62,
                   "mass": {"weight": -3.5}, "mass_by_configuration": {"efew": {"weight": -3.5}},
                   "flutter_speed": 1200.0},
    "gap_after": {"frequency_rms_held_out": 0.8, "mac_min": 0.97, "mass": {"weight": -0.2},
                  "mass_by_configuration": {"efew": {"weight": -0.2}}, "flutter_speed": None},
    "notes": ["calibration: mass +1.0 %"],
    "separating_measurement": None,
}


def test_no_diagnosis_no_section(tmp_path):
    assert diagnose_section(tmp_path, unit_labels("si")) == ""


def test_section_tables_with_units(tmp_path):
    (tmp_path / "diagnose").mkdir()
    (tmp_path / "diagnose" / "diagnose.json").write_text(json.dumps(RECORD))
    (tmp_path / "diagnose" / "gap.png").write_bytes(b"\x89PNG\r\n")
    page = diagnose_section(tmp_path, unit_labels("english_in"))
    assert "<b>effect</b>" in page
    assert ("<tr><td>1</td><td>joint_flexibility</td><td>grids: 5011, 5021; elements: 5100</td>"
            "<td>compliance = 3.2 +- 0.41</td><td>K1 = 1.5e+05, K4 = 2000</td><td>-</td></tr>"
            ) in page
    assert ("<tr><td>2</td><td>boundary_stiffness</td><td>grids: 204</td><td>k_z = 0.11 (not "
            "determined)</td>"
            "<td>K3 = 64</td><td>grid 148 z (+0.2)</td></tr>") in page
    assert "<td>2</td><td>lumped_mass</td><td>grid 3005</td><td>grids: 3005</td><td>42</td>" in page
    velocity = unit_labels("english_in").velocity
    for row in (("frequency_rms_held_out", "%", "4.1", "0.8"), ("mac_min", "-", "0.62", "0.97"),
                ("mass weight", "%", "-3.5", "-0.2"),
                ("mass_by_configuration efew weight", "%", "-3.5", "-0.2"),
                ("flutter_speed", velocity, "1200", "\u2013")):
        assert "<tr>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>" in page, row
    assert "calibration: mass +1.0 %" in page and 'alt="diagnose gap"' in page
