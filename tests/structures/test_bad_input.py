"""Bad decks fail early with the project's own errors naming the card, the id and the fix."""
from __future__ import annotations

import pytest

from pipeline.cli import main
from structures.bdf import read_model
from structures.common.errors import (InputError, MissingReferenceError, PipelineError, SolverError,
                               UnsupportedCardError)
from structures.modal import compute_modes

GOOD = """GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
GRID,3,,2.,0.,0.
CBAR,1,10,1,2,0.,1.,0.
CBAR,2,10,2,3,0.,1.,0.
PBAR,10,20,0.01,1.e-5,1.e-5,2.e-5
MAT1,20,7.e10,,0.3,2700.
CONM2,5,3,,2.0
SPC1,1,123456,1
"""


def _deck(tmp_path, text, name="deck.bdf"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_good_deck_reads(tmp_path):
    model = read_model(_deck(tmp_path, GOOD))
    assert compute_modes(model, 3)["frequency"].values[0] > 0


@pytest.mark.parametrize("text, error, words", [
    (GOOD.replace("PBAR,10", "PBAR,11"), MissingReferenceError, ["CBAR 1", "property 10", "Fix"]),
    (GOOD.replace("CBAR,2,10,2,3", "CBAR,2,10,2,4"), MissingReferenceError,
     ["CBAR 2", "grid 4", "Fix: add GRID 4"]),
    (GOOD + "CTETRA,7,10,1,2,3,1\n", UnsupportedCardError, ["CTETRA", "7", "Fix"]),
    (GOOD + "CQUAD8,8,10,1,2,3,1,,,\n", UnsupportedCardError, ["CQUAD8", "8", "Fix"]),
    (GOOD.replace("CONM2,5,3,,2.0", "CONM2,5,3,,-2.0"), InputError, ["CONM2 5", "positive"]),
    (GOOD + "CMASS2,9,0.,3,3\n", InputError, ["CMASS2 9", "positive"]),
    (GOOD.replace("MAT1,20", "MAT1,21"), MissingReferenceError, ["PBAR 10", "material 20"]),
    (GOOD.replace("CBAR,1,10,1,2,0.,1.,0.", "CBAR,1,10,1,2,1.,0.,0."), InputError,
     ["CBAR 1", "parallel", "orientation"]),
])
def test_bad_deck_raises_naming_card_id_and_fix(tmp_path, text, error, words):
    with pytest.raises(error) as info:
        compute_modes(read_model(_deck(tmp_path, text)), 3)
    message = str(info.value)
    for word in words:
        assert word in message, message
    assert "deck.bdf" in message


def test_all_unsupported_cards_listed_at_once(tmp_path):
    text = GOOD + "CTETRA,7,10,1,2,3,1\nCTETRA,8,10,1,2,3,2\nCHEXA,9,10,1,2,3,1,2,3\n,1,2\n"
    with pytest.raises(UnsupportedCardError) as info:
        read_model(_deck(tmp_path, text))
    assert "CTETRA (7, 8)" in str(info.value) and "CHEXA (9)" in str(info.value)


def test_mechanism_in_constrained_model_raises(tmp_path):
    """A hinge (pin flags releasing bending at the shared grid) with a tip mass: a mechanism."""
    hinged = GOOD.replace("CBAR,2,10,2,3,0.,1.,0.", "CBAR,2,10,2,3,0.,1.,0.\n,56").replace(
        "CBAR,1,10,1,2,0.,1.,0.", "CBAR,1,10,1,2,0.,1.,0.\n,,56")
    with pytest.raises(SolverError) as info:
        compute_modes(read_model(_deck(tmp_path, hinged)), 3)
    assert "mechanism" in str(info.value) and "grids moving most: [3" in str(info.value)


def test_spc_on_rigid_dependent_dof_raises(tmp_path):
    text = GOOD + "GRID,4,,3.,0.,0.\nRBE2,30,3,123456,4\nSPC1,1,3,4\n"
    with pytest.raises(InputError, match="dependent in a rigid element"):
        compute_modes(read_model(_deck(tmp_path, text)), 3)


def test_dof_dependent_in_two_rigid_elements_raises(tmp_path):
    text = GOOD + "GRID,4,,3.,0.,0.\nRBE2,30,3,123456,4\nRBE2,31,2,123,4\n"
    with pytest.raises(InputError, match="dependent in both RBE2 30 and RBE2 31"):
        compute_modes(read_model(_deck(tmp_path, text)), 3)


def test_cli_writes_nothing_on_error(tmp_path, capsys):
    bad = _deck(tmp_path, GOOD.replace("PBAR,10", "PBAR,11"))
    out = tmp_path / "modes.nc"
    assert main(["modes", str(bad), "--out", str(out)]) == 2
    assert not out.exists() and not list(tmp_path.glob("*.tmp"))
    assert "property 10" in capsys.readouterr().err


def test_errors_are_value_key_runtime_errors():
    assert issubclass(InputError, ValueError) and issubclass(MissingReferenceError, KeyError)
    assert issubclass(SolverError, RuntimeError) and issubclass(SolverError, PipelineError)
