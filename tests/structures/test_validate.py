"""Value and geometry checks at read time (structures.validate): each bad deck raises InputError or
MissingReferenceError naming the file, the card, the id and the fix, before any solve."""
from __future__ import annotations

import pytest

from structures.bdf import read_model
from structures.common.errors import InputError, MissingReferenceError
from structures.modal import compute_modes

#: A cantilever of two bars and a rod, a square plate of one CQUAD4 and one CTRIA3 beside it.
GOOD = """GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
GRID,3,,2.,0.,0.
GRID,4,,2.,1.,0.
GRID,5,,1.,1.,0.
GRID,6,,3.,0.,0.
CBAR,1,10,1,2,0.,1.,0.
CBAR,2,10,2,3,0.,1.,0.
CROD,3,11,3,6
PBAR,10,20,0.01,1.e-5,1.e-5,2.e-5
PROD,11,20,0.01,1.e-5
MAT1,20,7.e10,,0.3,2700.
CQUAD4,40,30,2,3,4,5
CTRIA3,41,30,3,6,4
PSHELL,30,20,0.002,20
CONM2,5,3,,2.0
SPC1,1,123456,1
"""
#: A unit square CQUAD4 42 on its own grids; grids 12 and 14 lifted by z2, grid 14 moved in plane.
#: The diagonals 11-13 and 12-14 lie z2 apart: folded when z2 / 2 > the half-diagonal 0.707.
QUAD_42 = """GRID,11,,0.,0.,0.
GRID,12,,1.,0.,{z2}
GRID,13,,1.,1.,0.
GRID,14,,{x4},{y4},{z2}
CQUAD4,42,30,11,12,13,14"""


def _read(tmp_path, text):
    path = tmp_path / "deck.bdf"
    path.write_text(text)
    return read_model(path)


def test_good_deck_gives_modes(tmp_path):
    assert compute_modes(_read(tmp_path, GOOD), 4)["frequency"].values[0] > 0


@pytest.mark.parametrize("old, new, words", [
    ("GRID,5,,1.,1.,0.", "GRID,5,,1.,NaN,0.", ["GRID 5", "not finite"]),
    ("PBAR,10,20,0.01,1.e-5", "PBAR,10,20,0.01,-1.e-5", ["PBAR 10", "I1", "negative"]),
    ("PBAR,10,20,0.01,1.e-5,1.e-5,2.e-5", "PBAR,10,20,0.01,1.e-5,1.e-5,2.e-5\n,\n,,,2.e-5",
     ["PBAR 10", "I12**2"]),
    ("PBAR,10,20,0.01", "PBAR,10,20,inf", ["PBAR 10", "A = inf", "not a finite"]),
    ("MAT1,20,7.e10,,0.3", "MAT1,20,7.e10,,0.7", ["MAT1 20", "NU = 0.7"]),
    ("MAT1,20,7.e10", "MAT1,20,-7.e10", ["MAT1 20", "E = -7", "negative"]),
    ("MAT1,20,7.e10,,0.3,2700.", "MAT1,20,7.e10,,0.3,nan", ["MAT1 20", "RHO"]),
    ("CROD,3,11,3,6", "CROD,3,11,3,6\nGRID,7,,2.,0.,0.\nCROD,4,11,3,7",
     ["CROD 4", "zero length"]),
    ("CTRIA3,41,30,3,6,4", "CTRIA3,41,30,3,6,6", ["CTRIA3 41", "zero area"]),
    ("CQUAD4,40,30,2,3,4,5", "CQUAD4,40,30,2,4,3,5", ["CQUAD4 40", "parallel diagonals"]),
    ("CQUAD4,40,30,2,3,4,5", "CQUAD4,40,30,2,3,4,5\n" + QUAD_42.format(z2=0.0, x4=0.8, y4=0.2),
     ["CQUAD4 42", "concave"]),
    ("CQUAD4,40,30,2,3,4,5", "CQUAD4,40,30,2,3,4,5\n" + QUAD_42.format(z2=1.5, x4=0.0, y4=1.0),
     ["CQUAD4 42", "folded"]),
    ("CQUAD4,40,30,2,3,4,5", "CQUAD4,40,30,2,3,4,5,,\n,,,-0.002", ["CQUAD4 40", "corner thick"]),
    ("PSHELL,30,20,0.002,20", "PSHELL,30,,0.002,,", ["PSHELL 30", "MID1 and MID2"]),
    ("CONM2,5,3,,2.0", "CONM2,5,3,,2.0,nan", ["CONM2 5", "non-finite"]),
    ("CONM2,5,3,,2.0", "CONM2,5,3,,2.0\nCMASS2,6,inf,3,3", ["CMASS2 6", "not positive"]),
    ("CONM2,5,3,,2.0", "CONM2,5,3,,2.0\nCELAS2,7,nan,3,3", ["CELAS2 7", "not a finite"]),
    ("CONM2,5,3,,2.0", "CONM2,5,3,,2.0\nGRID,9,,4.,0.,0.\nRBE3,60,,9,123456,nan,123,3,6",
     ["RBE3 60", "WT = nan"]),
    ("CBAR,1,10,1,2,0.,1.,0.", "CBAR,1,10,1,2,0.,1.,0.,XYZ", ["CBAR 1", "OFFT = 'XYZ'"]),
])
def test_bad_value_raises_naming_file_card_and_fix(tmp_path, old, new, words):
    assert old in GOOD
    with pytest.raises(InputError) as info:
        _read(tmp_path, GOOD.replace(old, new))
    message = str(info.value)
    for word in words + ["deck.bdf", "Fix:"]:
        assert word in message, message


def test_negative_grid_id_in_shell_is_a_missing_reference(tmp_path):
    with pytest.raises(MissingReferenceError) as info:
        _read(tmp_path, GOOD.replace("CQUAD4,40,30,2,3,4,5", "CQUAD4,40,30,2,3,4,-5"))
    assert "CQUAD4 40" in str(info.value) and "deck.bdf" in str(info.value)


@pytest.mark.parametrize("old, new", [("GRID,5,,1.,1.,0.", "GRID,5,,1.,1.e300,0."),
                                      ("PSHELL,30,20,0.002", "PSHELL,30,20,1.e300"),
                                      ("CONM2,5,3,,2.0", "CONM2,5,3,,2.e41")])
def test_huge_values_rejected_at_read(tmp_path, old, new):
    """Values beyond HUGE (1e40): products like E T^3 would overflow in the element matrices."""
    with pytest.raises(InputError, match=r"deck\.bdf, card (GRID 5|PSHELL 30|CONM2 5): .*1e\+?40"):
        _read(tmp_path, GOOD.replace(old, new))


def test_overflowing_values_raise_at_assembly(tmp_path):
    """A design change past the read checks (tuning's with_property) that overflows K:
    E A / L = 7e10 * 1e300 / 1."""
    model = _read(tmp_path, GOOD).with_property(10, A=1e300)
    with pytest.raises(InputError) as info:
        compute_modes(model, 4)
    assert "overflows" in str(info.value) and "deck.bdf" in str(info.value)
