"""CAERO1 box geometry (aero.panels): layout, numbering, normals, areas, bad input."""
from __future__ import annotations

import numpy as np
import pytest

from aero.panels import caero1_boxes, concat, mirror_xz
from structures.common.errors import InputError

U3 = np.linspace(0.0, 1.0, 4)


def test_rectangular_panel_layout():
    """Unswept 2 x 3 panel: corners, 1/4-chord doublet line, 3/4-chord collocation (exact)."""
    m = caero1_boxes(101, [0, 0, 0], 2.0, [0, 3, 0], 2.0, np.linspace(0, 1, 4),
                     np.linspace(0, 1, 3))
    assert m.n == 6
    np.testing.assert_array_equal(m.box_id, 101 + np.arange(6))      # chordwise fastest
    np.testing.assert_array_equal(m.panel_id, np.full(6, 101))
    # box 102 is the second chordwise box of the root strip: x in [1, 2], y in [0, 1]
    np.testing.assert_allclose(m.corners[1], [[1, 0, 0], [1, 1, 0], [2, 1, 0], [2, 0, 0]],
                               atol=1e-15)
    np.testing.assert_allclose(m.doublet_in[1], [1.25, 0, 0], atol=1e-15)
    np.testing.assert_allclose(m.doublet_out[1], [1.25, 1, 0], atol=1e-15)
    np.testing.assert_allclose(m.collocation[1], [1.75, 0.5, 0], atol=1e-15)
    np.testing.assert_allclose(m.normal, np.tile([0, 0, 1.0], (6, 1)))
    np.testing.assert_allclose(m.chord, 1.0)
    np.testing.assert_allclose(m.span, 1.0)
    np.testing.assert_allclose(m.area, 1.0)


def test_tapered_swept_panel_areas_and_points():
    """Trapezoid: box areas add up to the panel area; points lie on the stated chord fractions."""
    p1, p4, c1, c4 = np.array([0.0, 0, 0]), np.array([1.0, 4.0, 0.5]), 3.0, 1.0
    fs = np.array([0.0, 0.1, 0.4, 1.0])                          # uneven (AEFACT-like)
    fc = np.array([0.0, 0.3, 1.0])
    m = caero1_boxes(7, p1, c1, p4, c4, fs, fc)
    width = np.hypot(4.0, 0.5)
    np.testing.assert_allclose(m.area.sum(), 0.5 * (c1 + c4) * width, rtol=1e-14)
    # the collocation point of the last box (tip strip, rear box): s = 0.7, c = 0.3 + 0.75 * 0.7
    s, c = 0.7, 0.3 + 0.75 * 0.7
    chord = c1 + s * (c4 - c1)
    np.testing.assert_allclose(m.collocation[-1], p1 + s * (p4 - p1) + [c * chord, 0, 0],
                               rtol=1e-14)
    np.testing.assert_allclose(m.span[-1], 0.6 * width, rtol=1e-14)
    np.testing.assert_allclose(m.chord[-1], 0.7 * chord, rtol=1e-14)
    n = np.array([0.0, -0.5, 4.0]) / width                       # x_hat cross y_e
    np.testing.assert_allclose(m.normal, np.tile(n, (m.n, 1)), atol=1e-15)


@pytest.mark.parametrize("p4, normal", [([0, -3, 0], [0, 0, -1]),     # right-to-left: down
                                        ([0, 0, 3], [0, -1, 0]),      # fin bottom-up: port
                                        ([0, 0, -3], [0, 1, 0]),
                                        ([0, 3, 0], [0, 0, 1])])
def test_normal_rule(p4, normal):
    """Normal = x_hat x (p1 -> p4 direction), Nastran's CAERO1 element z axis."""
    m = caero1_boxes(1, [0, 0, 0], 1.0, p4, 1.0, U3, U3)
    np.testing.assert_allclose(m.normal, np.tile(normal, (m.n, 1)), atol=1e-15)
    np.testing.assert_allclose(m.span, 1.0)
    # corner 1 and the doublet line start on the p1 side of every box (p1 is the origin)
    yz = lambda a: np.linalg.norm(a[:, 1:], axis=1)                # noqa: E731
    assert np.all(yz(m.corners[:, 0]) < yz(m.corners[:, 1]))
    assert np.all(yz(m.doublet_in) < yz(m.doublet_out))


def test_first_box_id_and_concat():
    a = caero1_boxes(1000, [0, 0, 0], 1.0, [0, 1, 0], 1.0, U3, U3)
    b = caero1_boxes(2000, [0, 0, 0], 1.0, [0, -1, 0], 1.0, U3, U3, first_box_id=3000)
    m = concat([a, b])
    assert m.n == 18
    np.testing.assert_array_equal(m.box_id[9:], 3000 + np.arange(9))
    with pytest.raises(InputError, match="duplicate aerodynamic box ids"):
        concat([a, a])


def test_mirror_xz_normal_is_minus_mirrored_normal():
    a = caero1_boxes(1, [0, 0.5, 0], 1.0, [0.2, 2, 0.4], 0.8, U3, U3)
    im = mirror_xz(a)
    np.testing.assert_allclose(im.collocation[:, 1], -a.collocation[:, 1])
    np.testing.assert_allclose(im.normal, -(a.normal * [1, -1, 1]))


def test_arrays_are_read_only():
    a = caero1_boxes(1, [0, 0, 0], 1.0, [0, 1, 0], 1.0, U3, U3)
    with pytest.raises(ValueError):
        a.area[0] = 2.0


@pytest.mark.parametrize("p4, x12, x43", [([0.5, 0, 0], 1.0, 1.0),     # p4 = p1 in y-z
                                          ([0, 2, 0], 0.0, 0.0)])      # zero chords
def test_zero_area_panel_raises(p4, x12, x43):
    with pytest.raises(InputError, match=r"CAERO1 55.*zero-area panel.*Fix"):
        caero1_boxes(55, [0, 0, 0], x12, p4, x43, U3, U3)


@pytest.mark.parametrize("fs", [[0.0, 0.5, 0.4, 1.0], [0.1, 1.0], [0.0, 0.9], [0.0]])
def test_bad_fractions_raise(fs):
    with pytest.raises(InputError, match=r"CAERO1 9.*fractions"):
        caero1_boxes(9, [0, 0, 0], 1.0, [0, 1, 0], 1.0, fs, U3)


def test_negative_chord_raises():
    with pytest.raises(InputError, match=r"CAERO1 3.*negative chord"):
        caero1_boxes(3, [0, 0, 0], -1.0, [0, 1, 0], 1.0, U3, U3)


@pytest.mark.parametrize("p1, x12, fs", [([0, np.nan, 0], 1.0, U3), ([0, 0, 0], np.inf, U3),
                                         ([0, 0, 0], 1.0, [0.0, 1.0, 0.5])])
def test_bad_panel_names_the_deck(p1, x12, fs):
    """Non-finite corners or chords and bad fractions raise naming the deck that holds the CAERO1."""
    with pytest.raises(InputError, match=r"file wing\.bdf, card CAERO1 4: .*Fix"):
        caero1_boxes(4, p1, x12, [0, 1, 0], 1.0, fs, U3, filename="wing.bdf")
