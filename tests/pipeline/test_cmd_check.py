"""``pipeline check DECK``: cards, singularity table, mechanisms, coincident grids, free edges,
mass properties and the lowest modes, without any other analysis."""
from __future__ import annotations

from pathlib import Path

from pipeline.cli import main
from tests.structures.spring_decks import CHAIN_FREQUENCY, spring_chain

DATA = Path(__file__).resolve().parents[1] / "data"
WING = DATA / "practitioner_wing" / "wing.bdf"

# A square of four CRODs without a diagonal, its bottom grids 1, 2 clamped: the top grids 3, 4 can
# sway sideways together (a four-bar linkage), although each grid's x and y are stiff.
HINGED = """SOL 103
CEND
SPC = 1
BEGIN BULK
GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
GRID,3,,1.,1.,0.
GRID,4,,0.,1.,0.
MAT1,1,7.e10,,0.3,2700.
PROD,1,1,1.e-4
CROD,1,1,1,2
CROD,2,1,2,3
CROD,3,1,3,4
CROD,4,1,4,1
SPC1,1,123456,1,2
ENDDATA"""


def test_check_practitioner_wing(capsys):
    assert main(["check", str(WING), "--nmodes", "4"]) == 0
    out = capsys.readouterr().out
    assert "CBEAM" in out and "PBEAM" in out and "UNSUPPORTED" not in out
    assert "S I N G U L A R I T Y" in out and "240 singular directions at 60 grids" in out
    assert "3002 - 9000" in out and "free shell edges: 0" in out
    assert "mechanisms: none" in out and "x_cg" in out
    assert "6.21" in out                                  # first mode, Hz


def test_check_reports_a_mechanism_with_its_grids(tmp_path, capsys):
    deck = tmp_path / "hinged.bdf"
    deck.write_text(HINGED)
    assert main(["check", str(deck), "--nmodes", "3"]) == 1
    out = capsys.readouterr().out
    assert "mechanism:" in out and "grids moving most: [" in out
    moving = out.split("grids moving most: [")[1].split("]")[0]
    assert {int(g) for g in moving.split(",")[:2]} == {3, 4}   # the free grids first, not the clamped


def test_check_lists_unsupported_cards(tmp_path, capsys):
    deck = tmp_path / "solid.bdf"
    deck.write_text(HINGED.replace("ENDDATA", "CHEXA,99,1,1,2,3,1,2,3,\n,1,2\nENDDATA"))
    assert main(["check", str(deck)]) == 2
    out, err = capsys.readouterr()
    assert "UNSUPPORTED" in out and err.startswith("error: ") and "CHEXA (99)" in err


def test_check_says_when_the_model_has_fewer_modes_than_asked(tmp_path, capsys):
    """Three DOFs on springs, one with mass: its one mode, and why not the ten asked for."""
    assert main(["check", str(spring_chain(tmp_path / "chain.bdf"))]) == 0
    out = capsys.readouterr().out
    assert "all 1 of the model's modes (10 asked for; a model has as many as its degrees of " \
        "freedom that carry mass)" in out
    assert f"{CHAIN_FREQUENCY:.6f}" in out
