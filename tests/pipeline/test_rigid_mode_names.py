"""Rigid-body modes and roots named in the report: the participation table
(pipeline.selection.selection_table, shown by pipeline.report_tables.selection_section) when
participation.nc has ``rigid_motion(mode)``; the V-g overlay and the crossing table when flutter.nc
/ summary.json have ``root_label``."""
from __future__ import annotations

from flutter.results import crossings_of, stack_cases
from flutter.rigid_roots import label_rigid_roots
from pipeline.report import _crossing_table
from pipeline.report_figures import vg_overlay
from pipeline.selection import select_modes, selection_table
from structures.units import unit_labels
from tests.flutter.test_rigid_roots import OMEGA, _bff_sweep
from tests.pipeline.test_selection import participation


def test_participation_table_names_the_rigid_body_modes():
    """Modes 1-2 rigid (plunge, pitch) with 40 % of a flutter root: named under the rigid rows;
    without names the table is as before."""
    plain = participation([[15.0, 25.0, 50.0, 10.0]], [1, 2, 3, 4], rigid=(1, 2))
    named = plain.assign_coords(rigid_motion=("mode", ["plunge", "pitch", "", ""]))
    sel = select_modes({"EFEW": named}, primary=0.85, secondary=0.95)
    lines = selection_table(sel).splitlines()
    rigid_rows = [i for i, line in enumerate(lines) if "rigid " in line and "%" not in line]
    assert [lines[i].split()[:4] for i in rigid_rows[:2]] == [["1", "0", "-", "rigid"],
                                                               ["2", "0", "-", "rigid"]]
    assert lines[rigid_rows[1] + 1].strip() == "rigid-body modes: 1 plunge, 2 pitch"
    unnamed = selection_table(select_modes({"EFEW": plain}, primary=0.85, secondary=0.95))
    assert "rigid-body modes:" not in unnamed
    assert unnamed.splitlines() == [line for line in lines if "rigid-body modes:" not in line]


def test_report_names_rigid_roots_in_the_vg_legend_and_crossing_table():
    """The report's V-g overlay legend and crossing table show flutter.nc / summary.json labels."""
    ds, mass = _bff_sweep(9.0)
    sweep = label_rigid_roots(ds, mass, OMEGA, motions={1: "plunge", 2: "pitch"})
    fig = vg_overlay([stack_cases([sweep], [{"mach": 0.2}])], 0, ["stage 0"])
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert legend == ["root 1 (plunge)", "root 2 (short period)", "root 3"]
    html = _crossing_table(crossings_of(sweep), [], unit_labels("si"))
    assert "body_freedom_flutter" in html and "1 (plunge)" in html
