"""Rigid-body modes named in the participation table (pipeline.selection.selection_table, shown
by pipeline.report_tables.selection_section) when participation.nc has ``rigid_motion(mode)``."""
from __future__ import annotations

from pipeline.selection import select_modes, selection_table
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
