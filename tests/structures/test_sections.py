"""PBEAML beam-library sections (structures.sections) against hand formulas and explicit PBEAMs."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from structures.bdf import read_model
from structures.common.errors import InputError, UnsupportedCardError
from structures.modal import compute_modes
from structures.sections import section_fields, torsion_constant


def test_torsion_constants_against_closed_forms():
    """Circle and annulus exact; square bar 0.1406 a^4 (Timoshenko & Goodier, Table 10.1 /
    Roark); thin square tube a^3 t (Bredt); thin equal angle (2a - t) t^3 / 3."""
    r, ri = 0.1, 0.08
    assert torsion_constant("ROD", [r]) == pytest.approx(np.pi * r ** 4 / 2, rel=1e-14)
    assert torsion_constant("TUBE", [r, ri]) == pytest.approx(np.pi * (r ** 4 - ri ** 4) / 2,
                                                              rel=1e-14)
    a = 0.05
    assert torsion_constant("BAR", [a, a]) == pytest.approx(0.1406 * a ** 4, rel=2e-3)
    assert torsion_constant("BAR", [0.03, 0.005]) == torsion_constant("BAR", [0.005, 0.03])
    t = a / 500
    side = a - t                                                     # wall mid-line
    assert torsion_constant("BOX", [a, a, t, t]) == pytest.approx(side ** 3 * t, rel=1e-12)
    assert torsion_constant("L", [a, a, t, t]) == pytest.approx((2 * a - t) * t ** 3 / 3,
                                                                rel=1e-12)


def test_pbeaml_fields_single_and_two_stations():
    """One station: the BAR's b h, b h^3/12, h b^3/12; two stations of a linearly tapered BAR:
    the mean of the end values (pyNastran integrates X/XB linearly between two stations)."""
    b, h = 0.03, 0.005
    one = section_fields("PBEAML", 7, 1, "BAR", [[b, h]], [0.0], [0.2])
    assert (one["A"], one["I1"], one["I2"], one["I12"], one["NSM"]) == pytest.approx(
        (b * h, b * h ** 3 / 12, h * b ** 3 / 12, 0.0, 0.2), rel=1e-14)
    assert one["K1"] is None and one["K2"] is None
    two = section_fields("PBEAML", 7, 1, "BAR", [[b, h], [b, 2 * h]], [0.0, 1.0], [0.2, 0.4])
    def roark_j(a, t):   # Roark Table 10.7 case 4, a >= t
        return a * t ** 3 * (1 / 3 - 0.21 * (t / a) * (1 - t ** 4 / (12 * a ** 4)))

    ends = [{"A": b * hh, "I1": b * hh ** 3 / 12, "I2": hh * b ** 3 / 12, "J": roark_j(b, hh)}
            for hh in (h, 2 * h)]
    for key in ("A", "I1", "I2", "J"):
        assert two[key] == pytest.approx(0.5 * (ends[0][key] + ends[1][key]), rel=1e-12)
    assert two["NSM"] == pytest.approx(0.3, rel=1e-12)


def test_unsupported_section_type_names_the_card():
    with pytest.raises(UnsupportedCardError, match=r"PBEAML 12.*TYPE I .*ROD, TUBE, BAR, BOX, L"):
        section_fields("PBEAML", 12, 1, "I", [[1.0, 1.0, 1.0, 0.1, 0.1, 0.1]], [0.0], [0.0],
                       "wing.bdf")


def _cantilever(path: Path, prop: str) -> Path:
    """20 CBEAMs, 1 m, steel 0.03 x 0.005 m BAR bending in its stiff plane; one PLOTEL."""
    lines = ["SOL 103", "CEND", "SPC = 1", "METHOD = 1", "BEGIN BULK", "EIGRL,1,,,4",
             "MAT1,1,2.1E11,,0.3,7800.", prop, "SPC1,1,123456,1", "PLOTEL,900,1,21"]
    lines += [f"GRID,{i + 1},,{i / 20:.3f},0.,0." for i in range(21)]
    lines += [f"CBEAM,{i + 1},1,{i + 1},{i + 2},0.,0.,1." for i in range(20)]
    path.write_text("\n".join(lines + ["ENDDATA"]) + "\n")
    return path


def test_pbeaml_deck_equals_explicit_pbeam_and_euler_bernoulli(tmp_path):
    """A PBEAML BAR cantilever has the modes of the PBEAM carrying the same numbers (and, like the
    PBEAML, no shear flexibility), and its first bending frequency is Euler-Bernoulli's
    (1.8751^2 / 2 pi) sqrt(E I / (rho A L^4)) to 0.1 %."""
    b, h = 0.03, 0.005
    fields = section_fields("PBEAML", 1, 1, "BAR", [[b, h]], [0.0], [0.0])
    pbeaml = _cantilever(tmp_path / "pbeaml.bdf", f"PBEAML,1,1,,BAR\n,{b},{h}")
    pbeam = _cantilever(tmp_path / "pbeam.bdf", "PBEAM,1,1,{A!r},{I1!r},{I2!r},0.,{J!r}\n"
                        ",,,,,,,,\n,0.,0.".format(**fields))          # K1 = K2 = 0: no shear
    first = compute_modes(read_model(pbeaml), 4, mass="consistent")["frequency"].values
    second = compute_modes(read_model(pbeam), 4, mass="consistent")["frequency"].values
    np.testing.assert_allclose(first, second, rtol=1e-12)
    e_i = 2.1e11 * min(b * h ** 3, h * b ** 3) / 12
    analytic = 1.8751041 ** 2 / (2 * np.pi) * np.sqrt(e_i / (7800.0 * b * h * 1.0 ** 4))
    assert first[0] == pytest.approx(analytic, rel=1e-3)


def test_impossible_section_dimensions_name_the_card():
    """pyNastran checks DIMi with bare asserts (a BOX whose walls exceed half its width, a TUBE
    whose inner radius exceeds the outer): the project's InputError names the card instead."""
    with pytest.raises(InputError, match=r"wing\.bdf.*PBARL 3.*BOX section dimensions.*Fix"):
        section_fields("PBARL", 3, 1, "BOX", [[0.1, 0.1, 0.06, 0.06]], [0.0], [0.0], "wing.bdf")
    with pytest.raises(InputError, match=r"PBEAML 4.*TUBE"):
        section_fields("PBEAML", 4, 1, "TUBE", [[0.01, 0.02]], [0.0], [0.0], "wing.bdf")
