"""Matched-point flutter from a case's ``[flutter.matched]`` (pipeline.flight_points and
pipeline.chain).

References:
- U.S. Standard Atmosphere, 1976 (NOAA-S/T 76-1562), Table I (geometric altitude, SI): density
  and speed of sound at -1, 0, 5, 10, 15 and 20 km, as tabulated (5 significant figures for
  density, 3 decimals for the speed of sound);
- the english_in conversion by hand: 1 lbf = 4.4482216152605 N, 1 in = 0.0254 m (exact), so
  1 slinch = 1 lbf s^2/in = 175.1268352 kg and 1 slinch/in^3 = 1.0686894e7 kg/m^3;
- on the BAH wing deck (data/bah_wing/bah_plane.bdf, MKAERO1 Machs 0.0 and 0.2, AERO RHOREF
  1.225): the deck's own PKNL path, a FLUTTER PKNL card whose FLFACT lists hold the matched
  line's densities (as ratios to RHOREF), Mach numbers and velocities, solved by the same chain.
  The deck's wing flutters at Mach ~1.2 at sea level, far outside a subsonic matched line, so
  these tests soften it: every in-vacuo frequency x 0.15 (the rigid-body modes stay at 0 Hz),
  which puts a flutter crossing of the Mach 0.2 line at about 7,000 ft.
"""
from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from aero.model import read_aero_model
from flutter.atmosphere import KNOT, RHO0, atmosphere
from flutter.results import is_flutter
from flutter.system import StructuralDamping
from pipeline.case import MatchedSettings, read_case
from pipeline.chain import case_flutter, check_flutter_requests, deck_modes, flutter_chain
from pipeline.flight_points import line_altitudes, matched_requests
from pipeline.flutter_cards import deck_damping, read_flutter_requests
from structures.common.errors import InputError
from structures.common.files import read_dataset
from structures.common.nastran import read_pynastran
from tests.pipeline.bah_deck import DECK, deck_copy

SOFT = 0.15  # in-vacuo frequency factor of the softened wing

# US76 Table I: geometric altitude [m] -> (density [kg/m^3], speed of sound [m/s])
US76 = {-1000.0: (1.3470, 344.111), 0.0: (1.2250, 340.294), 5000.0: (0.73643, 320.545),
        10000.0: (0.41351, 299.532), 15000.0: (0.19476, 295.070), 20000.0: (0.088910, 295.070)}
SLINCH_PER_IN3 = (4.4482216152605 / 0.0254) / 0.0254 ** 3  # kg/m^3 per lbf s^2/in^4


def _quiet(fun, *args, **kw):
    with warnings.catch_warnings():
        # DLM box-size advice at the largest k; roots beyond the k table at the lowest speeds
        warnings.simplefilter("ignore", UserWarning)
        warnings.simplefilter("ignore", RuntimeWarning)
        return fun(*args, **kw)


def _flfact(sid: int, values) -> str:
    """A free-field FLFACT card with full-precision values (7 on the first line, 8 per
    continuation)."""
    values = [repr(float(v)) for v in values]
    lines = [",".join(["FLFACT", str(sid)] + values[:7])]
    lines += ["," + ",".join(values[i:i + 8]) for i in range(7, len(values), 8)]
    return "\n".join(lines) + "\n"


def _case(tmp_path: Path, flutter: str, units: str = "si") -> Path:
    path = tmp_path / "case.toml"
    path.write_text(f'name = "m"\nunits = "{units}"\n[[configurations]]\nname = "baseline"\n'
                    f'deck = "{DECK.as_posix()}"\nnmodes = 10\n{flutter}')
    return path


MATCHED = ('[flutter]\nstructural_damping = 0.01\n[flutter.matched]\n'
           'mach = [0.130, 0.160, 0.195, 0.284]\naltitude = [-1000.0, 20000.0]\n'
           'altitude_units = "ft"\npoints = 60\nmethod = "pknl"\n')


@pytest.fixture(scope="module")
def soft():
    modes = deck_modes(DECK)
    return modes.assign(frequency=modes["frequency"] * SOFT)


@pytest.fixture(scope="module")
def line(soft, tmp_path_factory):
    """The Mach 0.2 line of the softened wing, -1,000 .. 20,000 ft, 60 points, written out."""
    out = tmp_path_factory.mktemp("matched")
    matched = MatchedSettings(mach=(0.2,), altitude=(-1000.0, 20000.0), altitude_units="ft")
    return matched, out, _quiet(flutter_chain, DECK, soft, units="si", matched=matched,
                                out_dir=out)


# ---------------------------------------------------------------------------- flight points
def test_flight_points_against_the_us76_table():
    """Densities and V = M a(h) of a line through 20, 15, 10, 5 and 0 km against US76 Table I;
    V is M a(h) exactly (the same atmosphere), and the line runs from high to low."""
    matched = MatchedSettings(mach=(0.5, 0.8), altitude=(0.0, 20000.0), altitude_units="m",
                              points=5)
    h = line_altitudes(matched)
    np.testing.assert_array_equal(h, [20000.0, 15000.0, 10000.0, 5000.0, 0.0])
    reqs = matched_requests(matched, "si", StructuralDamping())
    assert [r.name for r in reqs] == ["Mach 0.500 matched line", "Mach 0.800 matched line"]
    assert [r.method for r in reqs] == ["PKNL", "PKNL"]
    for req, mach in zip(reqs, (0.5, 0.8)):
        assert req.mach == (mach,) * 5
        assert np.all(np.diff(req.density) > 0)
        np.testing.assert_array_equal(req.values, mach * atmosphere(h)["speed_of_sound"])
        for z, (rho, a) in US76.items():
            if z in h:
                i = int(np.flatnonzero(h == z)[0])
                assert req.density[i] == pytest.approx(rho, rel=5e-5)
                assert req.values[i] == pytest.approx(mach * a, rel=2e-6)
    # the table's -1 km row too (below sea level, the range of the case's example)
    atm = atmosphere(-1000.0)
    assert float(atm["density"]) == pytest.approx(US76[-1000.0][0], rel=5e-5)
    assert float(atm["speed_of_sound"]) == pytest.approx(US76[-1000.0][1], rel=2e-6)


def test_english_in_points_by_hand():
    """english_in: sea-level density 1.2250 kg/m^3 = 1.14627e-7 lbf s^2/in^4 and Mach 0.5 at
    340.294 m/s = 6698.70 in/s (by hand from the lbf and the inch); english_ft: 0.0023769
    slug/ft^3 and 558.226 ft/s."""
    assert 1.2250 / SLINCH_PER_IN3 == pytest.approx(1.14627e-7, rel=1e-5)  # the hand figure
    matched = MatchedSettings(mach=(0.5,), altitude=(0.0, 5000.0), altitude_units="m", points=2)
    (inch,) = matched_requests(matched, "english_in", StructuralDamping())
    (si,) = matched_requests(matched, "si", StructuralDamping())
    assert inch.density[-1] == pytest.approx(1.14627e-7, rel=1e-4)
    assert inch.values[-1] == pytest.approx(0.5 * 340.294 / 0.0254, rel=2e-6)
    assert inch.values[-1] == pytest.approx(6698.70, rel=2e-6)
    # flutter.atmosphere's slinch is 175.126835 kg (9 digits): 1.4e-9 from the exact one
    np.testing.assert_allclose(np.array(inch.density) * SLINCH_PER_IN3, si.density, rtol=3e-9)
    np.testing.assert_allclose(np.array(inch.values) * 0.0254, si.values, rtol=1e-15)
    (foot,) = matched_requests(matched, "english_ft", StructuralDamping())
    assert foot.density[-1] == pytest.approx(0.0023769, rel=1e-4)
    assert foot.values[-1] == pytest.approx(558.226, rel=2e-6)


def test_matched_requests_need_a_unit_system():
    matched = MatchedSettings(mach=(0.5,), altitude=(0.0, 5000.0), altitude_units="m")
    with pytest.raises(InputError, match="US76 atmosphere.*Fix: set the case's units"):
        matched_requests(matched, None, StructuralDamping())


# ---------------------------------------------------------------------------- on the BAH wing
def test_matched_line_equals_the_decks_pknl_card(soft, line, tmp_path):
    """The Mach 0.2 line gives the flutter point that the deck's own FLUTTER PKNL card, fed the
    same densities / Mach numbers / velocities, gives through the same chain (to 1e-10); the GAFs
    are computed at the line's Mach, one of the deck's MKAERO1 Machs."""
    matched, _, res = line
    assert read_aero_model(read_pynastran(DECK)).machs.tolist() == [0.0, 0.2]
    np.testing.assert_array_equal(res["gaf"]["mach"].values, [0.2])
    (req,) = matched_requests(matched, "si", StructuralDamping(), rhoref=1.225)
    cards = ("FLUTTER,503,PKNL,11,12,13\n" + _flfact(11, np.array(req.density) / 1.225)
             + _flfact(12, req.mach) + _flfact(13, req.values) + "ENDDATA")
    deck = deck_copy(tmp_path, lambda text: text.replace("ENDDATA", cards))
    (card,) = read_flutter_requests(read_pynastran(deck), str(deck), [503])
    np.testing.assert_allclose(card.density, req.density, rtol=1e-15)
    assert card.values == req.values and card.mach == req.mach
    via_card = _quiet(flutter_chain, deck, soft, units="si", flutter_ids=[503])
    ours = [c for c in res["summary"] if is_flutter(c["kind"])]
    theirs = [c for c in via_card["summary"] if is_flutter(c["kind"])]
    assert len(ours) == len(theirs) >= 1
    for a, b in zip(ours, theirs):
        assert (a["root"], a["mach"]) == (b["root"], b["mach"])
        for key in ("velocity", "density", "frequency"):
            assert a[key] == pytest.approx(b[key], rel=1e-10)
    assert ours[0]["configuration"] == "Mach 0.200 matched line"


def test_crossing_is_on_the_matched_line(line):
    """The flutter speed at the crossing is M a(h) at the crossing's altitude (the density
    altitude of its density), up to the crossing's linear interpolation of density and velocity
    between two of the 60 points, 108 m apart, while a(h(rho)) is not linear in rho (about
    dh^2 / 8H with H ~ 8.5 km: 0.17 m, 1e-4 m/s; measured 1.5e-6 relative); KTAS = V / 0.51444
    m/s, KEAS = V sqrt(rho / 1.225) / 0.51444; the altitude lies in the swept range."""
    matched, _, res = line
    flutter = [c for c in res["summary"] if is_flutter(c["kind"])]
    assert flutter
    for c in flutter:
        a = float(atmosphere(c["altitude"])["speed_of_sound"])
        assert c["velocity"] == pytest.approx(0.2 * a, rel=5e-6)
        assert float(atmosphere(c["altitude"])["density"]) == pytest.approx(c["density"],
                                                                           rel=1e-9)
        assert -304.8 <= c["altitude"] <= 6096.0
        assert c["ktas"] == pytest.approx(c["velocity"] / (1852 / 3600), rel=1e-12)
        assert c["keas"] == pytest.approx(c["velocity"] * np.sqrt(c["density"] / RHO0) / KNOT,
                                          rel=1e-12)
        assert c["units"]["altitude"] == "m" and c["units"]["keas"] == "kn"
    # the softened wing's first crossing: about 7,000 ft (2,146 m), 66.4 m/s, 0.47 Hz
    assert flutter[0]["altitude"] == pytest.approx(2146.0, abs=50.0)


def test_written_outputs_carry_the_flight_point(line):
    """summary.json (with altitude / KTAS / KEAS and their units), participation.nc (with the
    same labels) and flutter.nc hold the matched line's Mach, density and velocity of each
    crossing."""
    _, out, res = line
    summary = json.loads((out / "summary.json").read_text())
    assert summary == json.loads(json.dumps(res["summary"]))
    part = read_dataset(out / "participation.nc")
    flutter = [c for c in summary if is_flutter(c["kind"])]
    assert part.sizes["flutter_point"] == len(flutter)
    for i, c in enumerate(flutter):
        assert float(part["mach"][i]) == 0.2
        assert float(part["density"][i]) == c["density"]
        assert float(part["velocity"][i]) == c["velocity"]
        np.testing.assert_allclose(part["participation"].values[i].sum(), 100.0, rtol=1e-9)
        for key, unit in (("altitude", "m"), ("ktas", "kn"), ("keas", "kn")):
            assert float(part[key][i]) == c[key] and part[key].attrs["units"] == unit
    nc = read_dataset(out / "flutter.nc")
    assert str(nc["method"].values[0]) == "PKNL"
    np.testing.assert_array_equal(nc["mach_value"].values[0], np.full(60, 0.2))
    sweep = res["results"][0][1]
    np.testing.assert_allclose(sweep["altitude"].values, line_altitudes(line[0]), rtol=0)


def test_off_table_mach_gets_its_own_gafs(soft):
    """Mach 0.16 is not among MKAERO1's 0.0 and 0.2: the GAFs are computed at 0.16 itself
    (no interpolation in Mach)."""
    matched = MatchedSettings(mach=(0.16,), altitude=(0.0, 5000.0), altitude_units="m",
                              points=4)
    res = _quiet(flutter_chain, DECK, soft, units="si", matched=matched)
    np.testing.assert_array_equal(res["gaf"]["mach"].values, [0.16])
    assert {c["mach"] for c in res["summary"]} <= {0.16}
    assert res["results"][0][0]["configuration"] == "Mach 0.160 matched line"


# ---------------------------------------------------------------------------- damping
def test_matched_damping_from_the_case_or_the_decks_sdamp(tmp_path):
    """The case's g on every mode; else the SDAMP table of the FMETHOD subcase; subcases that
    disagree need the case's value."""
    bdf = read_pynastran(DECK)  # no SDAMP in its case control
    assert deck_damping(bdf, str(DECK)) == StructuralDamping()
    assert deck_damping(bdf, str(DECK), 0.01) == StructuralDamping(g=0.01, kind="viscous")
    deck = deck_copy(tmp_path, lambda text: text.replace(
        "  FMETHOD = 501\n", "  FMETHOD = 501\n  SDAMP = 2001\n"))
    # TABDMP1 2001: g = 0.01 at 0 Hz, 0.005 at 100 Hz
    assert deck_damping(read_pynastran(deck), str(deck)) == StructuralDamping(
        frequency=(0.0, 100.0), table_g=(0.01, 0.005), kind="viscous")
    two = deck_copy(tmp_path, lambda text: text.replace(
        "  FMETHOD = 501\n", "  FMETHOD = 501\n  SDAMP = 2001\n").replace(
        "$SUBCASE 2\n$  FMETHOD = 502\n", "SUBCASE 2\n  FMETHOD = 502\n"))
    with pytest.raises(InputError, match=r"bah_plane.bdf.*SDAMP.*Fix: set \[flutter\] "
                                         "structural_damping"):
        deck_damping(read_pynastran(two), str(two))
    assert deck_damping(read_pynastran(two), str(two), 0.02) == StructuralDamping(
        g=0.02, kind="viscous")


# ---------------------------------------------------------------------------- case file
def test_case_file_matched_table(tmp_path):
    case = read_case(_case(tmp_path, MATCHED))
    m = case.flutter.matched
    assert m == MatchedSettings(mach=(0.13, 0.16, 0.195, 0.284), altitude=(-1000.0, 20000.0),
                                altitude_units="ft", points=60, method="pknl")
    assert m.altitude_range_m == (-304.8, 6096.0)
    assert case.flutter.structural_damping == 0.01 and case.flutter.flutter_ids == ()
    check_flutter_requests(case)  # no FLUTTER id is needed
    assert read_case(_case(tmp_path, "[flutter]\n")).flutter.matched is None


@pytest.mark.parametrize("edit, needles", [
    (lambda t: t.replace("[flutter]\n", "[flutter]\nflutter_ids = [502]\n"),
     ("[flutter]", "flutter_ids = [502] and [flutter.matched]", "Fix: remove flutter_ids")),
    (lambda t: t.replace("points = 60", "point = 60"),
     ("[flutter.matched]", "unknown keys ['point']", "valid")),
    (lambda t: t.replace('altitude_units = "ft"\n', ""),
     ("[flutter.matched]", "'altitude_units' is required", "Fix: add altitude_units")),
    (lambda t: t.replace('"ft"', '"km"'),
     ("[flutter.matched]", "altitude_units = 'km'", "valid: ft, m")),
    (lambda t: t.replace("0.284]", "1.2]"),
     ("[flutter.matched]", "mach = [0.13, 0.16, 0.195, 1.2]", "Fix")),
    (lambda t: t.replace("0.284]", "0.13]"), ("[flutter.matched]", "repeats", "Fix")),
    (lambda t: t.replace("[-1000.0, 20000.0]", "[5000.0]"),
     ("[flutter.matched]", "altitude = [5000.0] must be a range", "Fix")),
    (lambda t: t.replace("[-1000.0, 20000.0]", "[0.0, 300000.0]"),
     ("[flutter.matched]", "outside the US76 atmosphere", "altitude_units")),
    (lambda t: t.replace("points = 60", "points = 1"), ("[flutter.matched]", "points = 1", "Fix")),
    (lambda t: t.replace('"pknl"', '"pk"'), ("[flutter.matched]", "method = 'pk'", "valid: pknl")),
    (lambda t: t.replace("points = 60", "points = 60.0"),
     ("[flutter.matched]", "points = 60.0 is a number; expected an integer", "points = 60")),
])
def test_case_file_errors(tmp_path, edit, needles):
    """Each message names the file, the table and the key, and the fix."""
    path = _case(tmp_path, edit(MATCHED))
    with pytest.raises(InputError) as err:
        read_case(path)
    text = str(err.value)
    assert str(path) in text
    for needle in needles:
        assert needle in text, (needle, text)


def test_command_line_flutter_id_conflicts_with_matched(tmp_path, soft):
    case = read_case(_case(tmp_path, MATCHED))
    with pytest.raises(InputError, match=r"--flutter-id.*\[flutter.matched\].*Fix"):
        check_flutter_requests(case, flutter_ids=[502])
    with pytest.raises(InputError, match=r"--flutter-id.*\[flutter.matched\].*Fix"):
        case_flutter(case, case.configurations[0], soft, flutter_ids=[502])


def test_case_flutter_runs_the_case_matched_lines(tmp_path, soft, line):
    """case_flutter (the flutter stage and ``pipeline flutter CASE``) runs the case's matched
    lines with its structural damping: the undamped line's crossings when g = 0, a later one with
    g = 0.03; and the flutter stage's declared settings change with [flutter.matched], so the
    stage reruns."""
    from dataclasses import replace

    from pipeline.stages import stage_plan

    flutter = ('[flutter]\nstructural_damping = {g}\n[flutter.matched]\nmach = [0.2]\n'
               'altitude = [-1000.0, 20000.0]\naltitude_units = "ft"\n')
    case = read_case(_case(tmp_path, flutter.format(g=0.0)))
    res = _quiet(case_flutter, case, case.configurations[0], soft)
    assert res["summary"] == line[2]["summary"]
    damped = read_case(_case(tmp_path, flutter.format(g=0.03)))
    res = _quiet(case_flutter, damped, damped.configurations[0], soft)
    undamped, with_g = ([c for c in r["summary"] if is_flutter(c["kind"])][0]
                        for r in (line[2], res))
    assert with_g["velocity"] > undamped["velocity"]

    def settings(c):
        (stage,) = [s for s in stage_plan(c, 0) if s.name == "stage0/flutter/baseline"]
        return stage.settings

    other = replace(case, flutter=replace(case.flutter, matched=replace(case.flutter.matched,
                                                                        points=30)))
    assert settings(other) != settings(case)
