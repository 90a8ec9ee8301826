"""CROD, CELAS1/2, CBUSH, CMASS2, PBARL and CBAR offsets against analytic or equivalent models."""
from __future__ import annotations

import numpy as np
import pytest

from structures.bdf import read_model
from structures.common.errors import UnsupportedCardError
from structures.modal import compute_modes


def _modes(tmp_path, text, n, name="d.bdf", **kw):
    path = tmp_path / name
    path.write_text(text)
    return compute_modes(read_model(path), n, **kw)["frequency"].values


def test_crod_axial_modes_fixed_free(tmp_path):
    """f_n = (2n - 1) / (4 L) sqrt(E / rho) (Blevins table 8-16), consistent mass, 40 rods."""
    nel, length, e, rho = 40, 2.0, 2.0e11, 7800.0
    lines = ["PARAM,COUPMASS,1", f"MAT1,1,{e},,0.3,{rho}", "PROD,1,1,1.e-4,1.e-8",
             "SPC1,1,123456,1"]
    lines += [f"GRID,{i + 1},,{length * i / nel!r},0.,0.,,23456" for i in range(nel + 1)]
    lines += [f"CROD,{i + 1},1,{i + 1},{i + 2}" for i in range(nel)]
    freq = _modes(tmp_path, "\n".join(lines) + "\n", 3)
    exact = (2 * np.arange(1, 4) - 1) / (4 * length) * np.sqrt(e / rho)
    np.testing.assert_allclose(freq, exact, rtol=2e-3)


def test_celas_and_cmass2_two_dof_system(tmp_path):
    """Two masses on springs k1 (to ground), k2 (between): closed-form eigenvalues."""
    k1, k2, m1, m2 = 4.0e4, 1.0e4, 2.0, 1.0
    text = (f"GRID,1,,0.,0.,0.,,1456\nGRID,2,,1.,0.,0.,,1456\nPELAS,7,{k1}\n"
            f"CELAS1,1,7,1,3\nCELAS2,2,{k2},1,3,2,3\nCELAS2,3,{k1},1,2\nCELAS2,4,{k1},2,2\n"
            f"CMASS2,10,{m1},1,3\nCMASS2,11,{m2},2,3\nCMASS2,12,1.,1,2\nCMASS2,13,1.,2,2\n")
    freq = _modes(tmp_path, text, 4)
    kmat = np.array([[k1 + k2, -k2], [-k2, k2]])
    lam = np.sort(np.linalg.eigvals(np.linalg.solve(np.diag([m1, m2]), kmat)).real)
    expected = np.sort(np.concatenate([np.sqrt(lam), [np.sqrt(k1), np.sqrt(k1)]])) / (2 * np.pi)
    np.testing.assert_allclose(freq, expected, rtol=1e-10)


def test_cbush_equals_celas_springs(tmp_path):
    """A CBUSH (CID=0) between coincident grids acts like six CELAS2 springs."""
    ks = [1.0e5, 2.0e5, 3.0e5, 4.0e3, 5.0e3, 6.0e3]
    base = ("GRID,1,,0.,0.,0.\nGRID,2,,0.,0.,0.\nSPC1,1,123456,1\n"
            "CONM2,9,2,,3.0\n,0.5,0.,0.7,0.,0.,0.9\n")
    bush = base + "CBUSH,5,6,1,2,,,,0\nPBUSH,6,K," + ",".join(map(str, ks)) + "\n"
    springs = base + "".join(f"CELAS2,{10 + c},{k},1,{c + 1},2,{c + 1}\n" for c, k in enumerate(ks))
    np.testing.assert_allclose(_modes(tmp_path, bush, 6, "b.bdf"),
                               _modes(tmp_path, springs, 6, "s.bdf"), rtol=1e-10)


def test_cbar_offsets_equal_rigid_links(tmp_path):
    """CBAR with end offsets WA/WB == CBAR between offset grids tied by RBAR to the grids."""
    common = ("MAT1,1,7.e10,,0.3,2700.\nPBAR,1,1,0.01,1.e-5,2.e-5,3.e-5\nPARAM,COUPMASS,1\n"
              "GRID,1,,0.,0.,0.\nGRID,2,,2.,0.,0.\nSPC1,1,123456,1\nCONM2,9,2,,5.\n,0.1,,0.2,,,0.3\n")
    offset = common + "CBAR,1,1,1,2,0.,1.,0.\n,,,0.,0.1,0.2,0.,0.1,0.2\n"
    linked = common + ("GRID,11,,0.,0.1,0.2\nGRID,12,,2.,0.1,0.2\nRBAR,21,1,11,123456,,,123456\n"
                       "RBAR,22,2,12,123456,,,123456\nCBAR,1,1,11,12,0.,1.,0.\n")
    np.testing.assert_allclose(_modes(tmp_path, offset, 8, "o.bdf"),
                               _modes(tmp_path, linked, 8, "l.bdf"), rtol=1e-10)


def test_pbarl_rod_section_equals_pbar(tmp_path):
    """PBARL ROD of radius r: A = pi r^2, I = pi r^4 / 4, J = pi r^4 / 2."""
    r = 0.05
    area, inertia = np.pi * r ** 2, np.pi * r ** 4 / 4
    common = ("MAT1,1,7.e10,,0.3,2700.\nSPC1,1,123456,1\nPARAM,COUPMASS,1\n" +
              "".join(f"GRID,{i + 1},,{0.25 * i!r},0.,0.\n" for i in range(9)) +
              "".join(f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,1.,0.\n" for i in range(8)))
    pbarl = common + f"PBARL,1,1,,ROD\n,{r}\n"
    pbar = common + f"PBAR,1,1,{area!r},{inertia!r},{inertia!r},{2 * inertia!r}\n"
    np.testing.assert_allclose(_modes(tmp_path, pbarl, 6, "l.bdf"),
                               _modes(tmp_path, pbar, 6, "p.bdf"), rtol=1e-8)


def test_pin_flag_equals_rbe2_hinge(tmp_path):
    """PA = 5 on the second segment is the same as a coincident grid tied by RBE2 with CM = 12346
    (a hinge about y); the tip is propped in z so the hinged model is stable. Lumped mass: the
    hinge grid's rotation is then massless, i.e. statically condensed, exactly as the pin flag."""
    common = ("MAT1,1,7.e10,,0.3,2700.\nPBAR,1,1,0.01,1.e-5,2.e-5,3.e-5\n"
              "SPC1,1,123456,1\nSPC1,1,3,9\nCONM2,7,5,,2.\n,1.e-3,,1.e-3,,,1.e-3\n" +
              "".join(f"GRID,{i + 1},,{0.5 * i!r},0.,0.\n" for i in range(8)) +
              "GRID,9,,4.,0.,0.\n" +
              "".join(f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,1.,0.\n" for i in range(3)) +
              "".join(f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,1.,0.\n" for i in range(4, 8)) +
              "CBAR,9,1,8,9,0.,1.,0.\n")
    pinned = common + "CBAR,4,1,4,5,0.,1.,0.\n,5\n"
    hinge = common + "GRID,44,,1.5,0.,0.\nRBE2,50,4,12346,44\nCBAR,4,1,44,5,0.,1.,0.\n"
    rigid = common + "CBAR,4,1,4,5,0.,1.,0.\n"
    f_pin = _modes(tmp_path, pinned, 6, "p.bdf")
    np.testing.assert_allclose(f_pin, _modes(tmp_path, hinge, 6, "h.bdf"), rtol=1e-9)
    assert np.max(np.abs(f_pin / _modes(tmp_path, rigid, 6, "r.bdf") - 1)) > 0.05


def test_pbarl_bar_torsion_constant_is_saint_venant(tmp_path):
    """PBARL BAR 30 x 10 mm: J is Saint-Venant's torsion constant (Roark, Table 10.7 case 4,
    a b^3 [1/3 - 0.21 (b/a)(1 - b^4/(12 a^4))] = 7.90e-9 m^4), not the polar moment I1 + I2
    (2.50e-8 m^4) that pyNastran's PBARL.J() returns: a free-free bar with its torsion mode among
    the lowest six elastic modes equals the PBAR with Roark's J."""
    a, b = 0.03, 0.01
    j = a * b ** 3 * (1 / 3 - 0.21 * (b / a) * (1 - b ** 4 / (12 * a ** 4)))
    area, i1, i2 = a * b, a * b ** 3 / 12, b * a ** 3 / 12   # QRG: DIM1 along the 2-axis
    bar = ("MAT1,1,7.e10,,0.3,2700.\nPARAM,COUPMASS,1\n" +
           "".join(f"GRID,{i + 1},,{0.1 * i!r},0.,0.\n" for i in range(11)) +
           "".join(f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,1.,0.\n" for i in range(10)) +
           # CBAR carries no torsional inertia: a small rotary inertia about the axis at each grid
           "".join(f"CONM2,{i + 101},{i + 1},,0.\n,1.e-3,,1.e-9,,,1.e-9\n" for i in range(11)))
    pbarl = _modes(tmp_path, bar + f"PBARL,1,1,,BAR\n,{a},{b}\n", 12, "b.bdf")
    pbar = _modes(tmp_path, bar + f"PBAR,1,1,{area!r},{i1!r},{i2!r},{j!r}\n", 12, "c.bdf")
    np.testing.assert_allclose(pbarl[6:], pbar[6:], rtol=1e-8)  # elastic modes, torsion among them
    assert np.all(pbarl[:6] < 1e-3 * pbarl[6])


def test_pbarl_section_type_without_properties_is_refused(tmp_path):
    path = tmp_path / "i.bdf"
    path.write_text("MAT1,1,7.e10,,0.3,2700.\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\n"
                    "CBAR,1,1,1,2,0.,1.,0.\nPBARL,1,1,,I\n,0.2,0.1,0.1,0.01,0.01,0.01\n")
    with pytest.raises(UnsupportedCardError, match=r"i\.bdf.*PBARL 1.*TYPE I.*Fix"):
        read_model(path)


def test_pinned_lumped_bar_mass_moves_along_its_axis():
    """A lumped CBAR along (1, 1, 0)/sqrt 2 with end A's axial translation released (PA = 1):
    end A follows end B axially (rigid in that direction), so by hand end A keeps m/2 across the
    bar, m/2 (I - x x^T), and end B carries m/2 I + m/2 x x^T (x the bar's axis), in basic axes."""
    from structures.elements.beam import beam_matrices

    x = np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0)
    one = np.ones(1)
    rho, area, length = 2700.0, 1.0e-4, 2.0
    _, m = beam_matrices(np.zeros((1, 3)), length * x[None], np.array([[0.0, 0.0, 1.0]]),
                         np.zeros((1, 3)), np.zeros((1, 3)), 7e10 * one, 2.6e10 * one,
                         area * one, 1e-8 * one, 2e-8 * one, 0 * one, 1e-8 * one, 0 * one,
                         rho * one, pins=np.array([1]), lumped=True)
    half = 0.5 * rho * area * length
    np.testing.assert_allclose(m[0, :3, :3], half * (np.eye(3) - np.outer(x, x)), atol=1e-12)
    np.testing.assert_allclose(m[0, 6:9, 6:9], half * (np.eye(3) + np.outer(x, x)), atol=1e-12)
    assert np.trace(m[0, :3, :3]) + np.trace(m[0, 6:9, 6:9]) == pytest.approx(6 * half)
