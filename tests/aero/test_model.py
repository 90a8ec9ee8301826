"""read_aero_model: reference values, frames, boxes, splines, Mach-k pairs and bad input."""
from __future__ import annotations

import numpy as np
import pytest

from aero.model import read_aero_model
from aero_decks import BAH, wing_grids, write_deck
from structures.common.errors import InputError, MissingReferenceError, UnsupportedCardError

PANEL = "PAERO1,1\nCAERO1,101,1,0,4,2,,,1\n,0.,0.,0.,2.,0.,6.,0.,2."


def test_bah_plane_reference_values_and_frames():
    """AERO fields, ACSID = CORD2R 2 (x and z flipped) and the CP frames of both CAERO1 panels."""
    m = read_aero_model(BAH)
    assert (m.refc, m.rhoref, m.velocity, m.symxz, m.symxy) == (4.0, 1.225, 1.0, 1, 0)
    np.testing.assert_allclose(m.aero_frame.axes, np.diag([-1.0, 1.0, -1.0]), atol=1e-12)
    assert m.mesh.n == 200 + 28
    np.testing.assert_array_equal(m.mesh.box_id[:3], [601, 602, 603])
    np.testing.assert_array_equal(m.mesh.box_id[-28:], np.arange(901, 929))
    # wing: CP = 2, P1 = (-2, 0, 0) in CP 2 -> basic (2, 0, 0); root chord 5.7 downstream = -x basic
    wing = m.mesh.corners[m.mesh.panel_id == 601]
    np.testing.assert_allclose(m.to_basic(wing[0, 0]), [2.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(m.to_basic(wing[9, 3]), [2.0 - 5.7, 0.0, 0.0], atol=1e-12)
    # tail: CP = 3 (origin (-13, 0, -0.5), x = -x basic): P1 = (-2, 0, 0) -> basic (-11, 0, -0.5)
    tail = m.mesh.corners[m.mesh.panel_id == 901]
    np.testing.assert_allclose(m.to_basic(tail[0, 0]), [-11.0, 0.0, -0.5], atol=1e-12)
    np.testing.assert_allclose(m.to_basic(tail[-1, 2]), [-11.5 - 2.0, 5.0, -0.5], atol=1e-12)
    assert [s.kind for s in m.splines] == ["BEAM", "BEAM"]
    s1, s2 = m.splines
    np.testing.assert_array_equal(s1.grid_ids, np.arange(1, 7))
    assert (s1.box1, s1.box2, s1.dz, s1.dtor, s1.usage) == (601, 800, 0.0, 1.0, "BOTH")
    assert (s2.box1, s2.box2, s2.dz, s2.frame.cid) == (901, 928, 1.0, 3)
    np.testing.assert_allclose(s2.grid_xyz[:, 2], -0.5)
    np.testing.assert_allclose(s2.frame.origin, [-13.0, 0.0, -0.5])


def test_bah_plane_mkaero1_pairs_in_card_order():
    """Two MKAERO1 cards x (2 Mach x 8 k) and (2 Mach x 7 k): 30 pairs, Mach-major per card."""
    m = read_aero_model(BAH)
    assert m.mach_k.shape == (30, 2)
    np.testing.assert_allclose(m.mach_k[:8, 0], 0.0)
    np.testing.assert_allclose(m.mach_k[8:16, 0], 0.2)
    np.testing.assert_allclose(m.mach_k[:8, 1], [0.001, 0.05, 0.1, 0.2, 0.5, 1.0, 1.2, 1.5])
    np.testing.assert_allclose(m.mach_k[16:23, 1], [2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 10.0])
    assert m.ks.size == 15 and m.machs.tolist() == [0.0, 0.2]


def test_aefact_divisions_cp_frame_set1_thru_mkaero2(tmp_path):
    """Uneven AEFACT divisions, a translated+rotated CP frame, SET1 THRU and MKAERO2 pairs."""
    bulk = "\n".join([
        wing_grids(),
        "CORD2R,7,0,10.,0.,1.,10.,0.,2.,+C7\n+C7,10.,-1.,1.",  # origin (10,0,1); x_cp = -y basic
        "PAERO1,1",
        "CAERO1,101,1,7,,,11,12,1\n,0.,0.,0.,2.,-6.,0.,0.,1.",
        "AEFACT,11,0.,.5,.8,1.", "AEFACT,12,0.,.25,1.",
        "SET1,5,1,THRU,12",
        "SPLINE1,201,101,101,106,5,0.",
        "MKAERO2,0.3,0.1,0.5,0.4",
    ])
    m = read_aero_model(write_deck(tmp_path / "d.bdf", bulk))
    pan = m.panels[0]
    np.testing.assert_allclose(pan.span_fractions, [0.0, 0.5, 0.8, 1.0])
    np.testing.assert_allclose(pan.chord_fractions, [0.0, 0.25, 1.0])
    # CP 7: local x -> basic -y, z -> basic +z: P1 (0,0,0) -> (10,0,1); P4 (-6,0,0) -> (10,6,1)
    np.testing.assert_allclose(pan.p1, [10.0, 0.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(pan.p4, [10.0, 6.0, 1.0], atol=1e-12)
    np.testing.assert_array_equal(m.mesh.box_id, np.arange(101, 107))
    # second spanwise strip starts at 0.5 span, second chordwise box at 0.25 chord
    np.testing.assert_allclose(m.mesh.corners[2, 0], [10.0, 3.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(m.mesh.corners[1, 0, 0], 10.0 + 0.25 * 2.0, atol=1e-12)
    np.testing.assert_array_equal(m.splines[0].grid_ids, np.arange(1, 13))
    np.testing.assert_allclose(m.mach_k, [[0.3, 0.1], [0.5, 0.4]])


def _deck(tmp_path, bulk):
    return write_deck(tmp_path / "bad.bdf", wing_grids() + "\n" + bulk)


def test_missing_set1_names_spline_and_fix(tmp_path):
    path = _deck(tmp_path, PANEL + "\nSPLINE1,201,101,101,108,99")
    with pytest.raises(MissingReferenceError, match=r"SPLINE1 201.*SETG=99.*SET1"):
        read_aero_model(path)


def test_spline_box_range_outside_caero(tmp_path):
    path = _deck(tmp_path, PANEL + "\nSET1,5,1,THRU,12\nSPLINE1,201,101,101,120,5")
    with pytest.raises(InputError, match=r"SPLINE1 201.*101\.\.120.*101\.\.108"):
        read_aero_model(path)


def test_overlapping_splines_rejected(tmp_path):
    path = _deck(tmp_path, PANEL + "\nSET1,5,1,THRU,12\nSPLINE1,201,101,101,105,5\n"
                 "SPLINE1,202,101,104,108,5")
    with pytest.raises(InputError, match=r"box 104 is already interpolated by SPLINE1 201"):
        read_aero_model(path)


def test_bodies_and_other_aero_cards_rejected(tmp_path):
    body = "PAERO1,1,301\nCAERO1,101,1,0,4,2,,,1\n,0.,0.,0.,2.,0.,6.,0.,2."
    with pytest.raises(UnsupportedCardError, match=r"PAERO1 1 with body ids"):
        read_aero_model(_deck(tmp_path, body))
    caero2 = (PANEL + "\nPAERO2,2,Z,1.,1.,,,\nCAERO2,301,2,0,4,2,,,1\n,0.,0.,0.,5.")
    with pytest.raises(UnsupportedCardError, match=r"CAERO2"):
        read_aero_model(_deck(tmp_path, caero2))
    tps = PANEL + "\nSET1,5,1,THRU,12\nSPLINE1,201,101,101,108,5,0.,TPS"
    with pytest.raises(UnsupportedCardError, match=r"SPLINE1 201.*METH=TPS"):
        read_aero_model(_deck(tmp_path, tps))


def test_zero_area_panel_and_missing_aefact(tmp_path):
    flat = "PAERO1,1\nCAERO1,101,1,0,4,2,,,1\n,0.,0.,0.,2.,3.,0.,0.,2."
    with pytest.raises(InputError, match=r"CAERO1 101.*zero-area"):
        read_aero_model(_deck(tmp_path, flat))
    lspan = "PAERO1,1\nCAERO1,101,1,0,,2,44,,1\n,0.,0.,0.,2.,0.,6.,0.,2."
    with pytest.raises(MissingReferenceError, match=r"CAERO1 101.*AEFACT"):
        read_aero_model(_deck(tmp_path, lspan))


def test_symxy_and_missing_aero_rejected(tmp_path):
    with pytest.raises(UnsupportedCardError, match=r"SYMXY"):
        read_aero_model(write_deck(tmp_path / "a.bdf", PANEL, aero="AERO,0,1.,2.,1.225,0,1"))
    with pytest.raises(InputError, match=r"no AERO or AEROS"):
        read_aero_model(write_deck(tmp_path / "b.bdf", PANEL, aero=""))


@pytest.mark.parametrize("caero, words", [
    ("CAERO1,101,1,0,99999999,2,,,1", r"bad\.bdf, card CAERO1 101: NSPAN=99999999"),
    ("CAERO1,101,1,0,30000,2,,,1", r"bad\.bdf: the CAERO1 panels divide into 60000 boxes"),
])
def test_absurd_box_counts_rejected_before_meshing(tmp_path, caero, words):
    """A mistyped NSPAN fails at read, before the box arrays (and an AIC of 16 n^2 bytes)."""
    with pytest.raises(InputError, match=words):
        read_aero_model(_deck(tmp_path, PANEL.replace("CAERO1,101,1,0,4,2,,,1", caero)))


def test_bad_spline_values_name_the_deck(tmp_path):
    """Spline flexibilities are checked with the deck named in the message."""
    splines = PANEL + "\nSET1,5,1,THRU,12\nSPLINE2,201,101,101,108,5,nan,1.,0"
    with pytest.raises(InputError, match=r"bad\.bdf, card SPLINE2 201: DZ=nan"):
        read_aero_model(_deck(tmp_path, splines))


def test_supersonic_mkaero_rejected_at_read(tmp_path):
    """The doublet lattice is subsonic: an MKAERO1 Mach of 1.2 fails at read, naming the deck."""
    path = _deck(tmp_path, PANEL + "\nMKAERO1,0.5,1.2\n,0.1,0.2")
    with pytest.raises(InputError, match=r"bad\.bdf, card MKAERO1: .*>= 1"):
        read_aero_model(path)
