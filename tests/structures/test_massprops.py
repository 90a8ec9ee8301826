"""Mass properties against hand calculations (offset CONM2s with inertia, CMASS2)."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from structures.bdf import read_model
from structures.common.errors import InputError
from structures.massprops import mass_properties

DATA = Path(__file__).resolve().parents[1] / "data"

DECK = """GRID,1,,0.,0.,0.
GRID,2,,2.,0.,0.
GRID,3,,2.,1.,0.
CELAS2,10,1.e6,1,3,2,3
CELAS2,11,1.e6,2,3,3,3
CONM2,1,1,,10.,0.5,0.2,0.1
,1.,0.,2.,0.,0.,3.
CONM2,2,2,,4.,0.,0.,-1.
CONM2,3,3,,6.,-0.5,0.5,0.
,0.5,0.1,0.8,0.2,0.3,0.9
ENDDATA
"""


def _hand(masses):
    """Total mass, CG and inertia about the CG from (m, position, inertia tensor) triples."""
    total = sum(m for m, _, _ in masses)
    cg = sum(m * np.asarray(r) for m, r, _ in masses) / total
    inertia = np.zeros((3, 3))
    for m, r, i_cg in masses:
        d = np.asarray(r) - cg
        inertia += i_cg + m * (np.dot(d, d) * np.eye(3) - np.outer(d, d))
    return total, cg, inertia


def test_offset_conm2_mass_properties_match_hand_calculation(tmp_path):
    path = tmp_path / "masses.bdf"
    path.write_text(DECK)
    props = mass_properties(read_model(path))
    # CONM2 inertia tensor: [[I11, -I21, -I31], [-I21, I22, -I32], [-I31, -I32, I33]] (QRG CONM2).
    i1 = np.array([[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]])
    i3 = np.array([[0.5, -0.1, -0.2], [-0.1, 0.8, -0.3], [-0.2, -0.3, 0.9]])
    mass, cg, inertia = _hand([(10.0, (0.5, 0.2, 0.1), i1), (4.0, (2.0, 0.0, -1.0), np.zeros((3, 3))),
                               (6.0, (1.5, 1.5, 0.0), i3)])
    assert props.mass == pytest.approx(mass, rel=1e-14)
    np.testing.assert_allclose(props.cg, cg, rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(props.inertia, inertia, rtol=1e-13, atol=1e-13)
    assert props.product_of_inertia["Ixy"] == pytest.approx(-inertia[0, 1])


def test_wtmass_scales_mass_and_weight_is_recovered(tmp_path):
    path = tmp_path / "wt.bdf"
    path.write_text("PARAM,WTMASS,0.00259\n" + DECK)
    props = mass_properties(read_model(path))
    assert props.mass == pytest.approx(20.0 * 0.00259, rel=1e-14)
    assert props.weight == pytest.approx(20.0, rel=1e-14)


def test_bah_total_mass_equals_sum_of_conm2():
    props = mass_properties(read_model(DATA / "bah_plane" / "bah_plane.bdf"))
    wing = 2 * (1364.8 + 2305.2 + 949.2 + 768.4 + 153.68)
    assert props.mass == pytest.approx(7864.8 + wing, rel=1e-14)
    # Symmetric fore/aft masses at x = +/-: CG x from the CONM2 positions (GRID 7..16).
    xs = {7: 1.126, 8: 2.751, 9: .7034, 10: .6725, 11: .5060, 12: -.7709, 13: -2.053, 14: -.8050,
          15: -.7740, 16: -.7091}
    ms = {7: 1364.8, 8: 2305.2, 9: 949.2, 10: 768.4, 11: 153.68}
    ms.update({k + 5: v for k, v in ms.items()})
    x_cg = sum(ms[g] * xs[g] for g in xs) / props.mass
    assert props.cg[0] == pytest.approx(x_cg, rel=1e-12)


def test_measured_mass_json(tmp_path):
    from structures.massprops import read_measured_mass

    path = tmp_path / "mass.json"
    path.write_text('{"weight": 480.5, "cg": [1.0, 0.0, -2.5], '
                    '"inertia_cg": [10.0, 20.0, 30.0, 0.5, -0.25, 0.125]}')
    assert read_measured_mass(path) == {"weight": 480.5, "x_cg": 1.0, "y_cg": 0.0, "z_cg": -2.5,
                                        "Ixx": 10.0, "Iyy": 20.0, "Izz": 30.0, "Ixy": 0.5,
                                        "Izx": -0.25, "Iyz": 0.125}
    path.write_text('{"weight": 480.5}')
    assert read_measured_mass(path) == {"weight": 480.5}
    for text, words in (('{"weight": 1.0, "cog": [1, 2, 3]}', "unknown keys ['cog']"),
                        ('{"cg": [1.0, 2.0]}', "cg = [1.0, 2.0] is not a list of 3 finite"),
                        ('{"weight": "heavy"}', "weight = 'heavy' is not a finite number"),
                        ('{"weight": 1.0,}', "not valid JSON"),
                        ('[1.0, 2.0]', "holds a JSON list, not an object"),
                        ('{}', "names no quantity")):
        path.write_text(text)
        with pytest.raises(InputError, match=re.escape(words)):
            read_measured_mass(path)
    with pytest.raises(InputError, match="no such measured-mass file"):
        read_measured_mass(tmp_path / "none.json")


def _inertia_json(inertia) -> dict:
    """[Ixx, Iyy, Izz, Ixy, Ixz, Iyz] of the file format from a (3, 3) inertia tensor
    (products Ixy = sum m x y, the tensor's off-diagonals negated)."""
    return [inertia[0, 0], inertia[1, 1], inertia[2, 2], -inertia[0, 1], -inertia[0, 2],
            -inertia[1, 2]]


def test_measured_inertia_must_be_a_bodys(tmp_path):
    """A flat cloud of point masses (Izz = Ixx + Iyy, its z second moment zero) turned about
    every axis passes, with a swing test's 2 % error on Izz too; Izz raised by 20 % of itself
    (its second moment -10 % of Izz, 8.3 % of the raised one), products five times too large or
    a negative moment are refused."""
    import json

    from structures.massprops import read_measured_mass

    rng = np.random.default_rng(3)
    points = [(float(m), rng.normal(size=3) * (2.0, 1.0, 0.0), np.zeros((3, 3)))
              for m in rng.uniform(1.0, 5.0, 12)]
    _, _, flat = _hand(points)
    assert np.isclose(flat[2, 2], flat[0, 0] + flat[1, 1])
    c, s = np.cos(0.7), np.sin(0.7)
    turn = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]) @ \
        np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    path = tmp_path / "mass.json"

    def read(values):
        path.write_text(json.dumps({"weight": 10.0, "inertia_cg": [float(v) for v in values]}))
        return read_measured_mass(path)

    read(_inertia_json(flat))
    read(_inertia_json(turn @ flat @ turn.T))
    heavy_z = flat.copy()
    heavy_z[2, 2] *= 1.02
    read(_inertia_json(heavy_z))
    too_heavy = flat.copy()
    too_heavy[2, 2] *= 1.2
    with pytest.raises(InputError, match=r"not a body's inertia: with the products, a second "
                                         r"moment of mass comes to -[0-9.]+, below zero by 8\.3 %"):
        read(_inertia_json(too_heavy))
    big = _inertia_json(turn @ flat @ turn.T)
    big[3:] = [5.0 * v for v in big[3:]]
    with pytest.raises(InputError, match=r"not a body's inertia.*Fix: check that no moment "
                                         r"exceeds the sum of the other two"):
        read(big)
    with pytest.raises(InputError, match=re.escape("moments of inertia ['Iyy'] must not be "
                                                   "negative")):
        read([10.0, -1.0, 10.0, 0.0, 0.0, 0.0])
    with pytest.raises(InputError, match=re.escape("nor all zero")):
        read([0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    read([0.0, 20.9, 20.9, 0.0, 0.0, 0.0])          # masses on a line along x: Ixx = 0


@pytest.mark.parametrize("cg, refused", [
    ((1.0, 0.5, 0.0), None),
    ((2.09, 1.55, -1.09), None),          # within 5 % of the largest side (2) of every edge
    ((2.11, 0.5, 0.0), "x_cg = 2.11 (the model spans 0 .. 2)"),
    ((1.0, 1.61, 0.0), "y_cg = 1.61 (the model spans 0 .. 1.5)"),
    ((1.0, 0.5, 0.0254 * 10.0), "z_cg = 0.254 (the model spans -1 .. 0.1)"),
])
def test_measured_cg_must_lie_within_the_model(tmp_path, cg, refused):
    """DECK's grids span x 0..2, y 0..1, z 0; its CONM2 centres (grid + offset: (0.5, 0.2, 0.1),
    (2, 0, -1), (1.5, 1.5, 0)) widen y to 1.5 and z to -1..0.1 (by hand); the margin is 5 % of
    the largest side, 0.1."""
    from structures.massprops import check_cg_inside

    path = tmp_path / "masses.bdf"
    path.write_text(DECK)
    model = read_model(path)
    measured = dict(zip(("x_cg", "y_cg", "z_cg"), cg), weight=20.0)
    if refused is None:
        check_cg_inside(measured, model, "mass.json")
        return
    with pytest.raises(InputError) as err:
        check_cg_inside(measured, model, "mass.json")
    for needle in ("mass.json: the measured CG lies outside the model", refused,
                   "Fix: give the CG in the deck's length unit and basic axes"):
        assert needle in str(err.value), (needle, str(err.value))
