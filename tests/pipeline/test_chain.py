"""The one modes -> GAFs -> flutter chain (pipeline.chain) on the BAH wing deck.

References: Nastran's F06 for this deck (FLUTTER 502, PK at M 0.2, sea level: flutter at 394.0 m/s,
3.18 Hz); the participation definition evaluated by hand on the stored crossing eigenvectors; the
deck's own SDAMP / TABDMP1 route for the case's constant structural damping; ``pipeline flutter
CASE`` against the library calls it makes.
"""
from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from flutter.results import is_flutter
from flutter.solve import SOLVERS
from flutter.system import StructuralDamping
from pipeline.case import read_case
from pipeline.chain import (case_flutter, configuration_modes, deck_modes, flutter_chain,
                            flutter_participation)
from pipeline.cli import main
from pipeline.flutter_cards import read_flutter_requests
from structures.common.errors import UnsupportedCardError
from structures.common.files import read_dataset
from structures.common.nastran import read_pynastran
from tests.pipeline.bah_deck import DECK, deck_copy


def _chain(deck, modes, **kw):
    with warnings.catch_warnings():
        # DLM box-size advice at the largest k; roots 9-10 beyond the k table at 30 m/s
        warnings.simplefilter("ignore", UserWarning)
        warnings.simplefilter("ignore", RuntimeWarning)
        return flutter_chain(deck, modes, flutter_ids=[502], **kw)


def _flutter(result) -> list[dict]:
    return [c for c in result["summary"] if is_flutter(c["kind"])]


@pytest.fixture(scope="module")
def modes():
    return deck_modes(DECK)


@pytest.fixture(scope="module")
def plain(modes, tmp_path_factory):
    out = tmp_path_factory.mktemp("chain")
    return out, _chain(DECK, modes, units="si", out_dir=out)


@pytest.fixture(scope="module")
def damped(modes):
    return _chain(DECK, modes, structural_damping=0.03)


def test_bah_flutter_point_against_nastran(plain):
    """FLUTTER 502: one flutter crossing, speed within 2 % and frequency within 3 % of Nastran's
    394.0 m/s, 3.18 Hz (measured 395.1 m/s, 3.183 Hz)."""
    _, res = plain
    fl = _flutter(res)
    assert len(fl) == 1
    assert fl[0]["velocity"] == pytest.approx(394.0, rel=0.02)
    assert fl[0]["frequency"] == pytest.approx(3.18, rel=0.03)


def test_participation_nc_layout(plain, modes):
    """participation.nc as the contract says: dims, coordinates, attrs, units; sums to 100 per
    point; the numbers equal m_j |u_j|^2 / sum_k m_k |u_k|^2 (diagonal M_hh) of the crossing
    eigenvector, computed here by hand."""
    out, res = plain
    ds = read_dataset(out / "participation.nc")
    assert sorted(ds.dims) == ["flutter_point", "mode"]
    assert ds["participation"].dims == ("flutter_point", "mode")
    assert ds["participation"].attrs["units"] == "%"
    for name in ("case", "mach", "density", "velocity", "frequency", "root", "flutter_mode"):
        assert ds[name].dims == ("flutter_point",), name
    for name in ("rigid", "fe_frequency"):
        assert ds[name].dims == ("mode",), name
    assert ds.attrs["configuration"] == "bah_plane"
    assert ds.attrs["units"] == "si" and ds.attrs["rigid_hz"] == 0.05
    assert ds["velocity"].attrs["units"] == "m/s" and ds["frequency"].attrs["units"] == "Hz"
    assert ds.sizes["flutter_point"] == 1 and ds.sizes["mode"] == 10
    np.testing.assert_allclose(ds.participation.sum("mode"), 100.0, rtol=1e-12)
    crossing = _flutter(res)[0]
    point = ds.isel(flutter_point=0)
    assert int(point.case) == crossing["case"] == 0 and int(point.root) == crossing["root"]
    assert int(point.flutter_mode) == 1
    assert float(point.velocity) == crossing["velocity"]
    assert float(point.frequency) == crossing["frequency"]
    assert float(point.mach) == pytest.approx(0.2) and float(point.density) == pytest.approx(1.225)
    # the free plunge and pitch modes (0 Hz) are the rigid ones; the rest are the wing's
    np.testing.assert_array_equal(ds.rigid.values, modes["frequency"].values < 0.05)
    assert int(ds.rigid.sum()) == 2
    np.testing.assert_array_equal(ds.fe_frequency.values, modes["frequency"].values)
    _, sweep = res["results"][0]
    i = int(np.flatnonzero(sweep.crossing_kind.values == "flutter")[0])
    u = sweep.crossing_eigenvector.values[i]
    m = modes["generalized_mass"].values
    by_hand = 100 * m * np.abs(u) ** 2 / np.sum(m * np.abs(u) ** 2)
    np.testing.assert_allclose(ds.participation.values[0], by_hand, rtol=1e-10, atol=1e-12)
    assert {p.name for p in out.iterdir()} >= {"flutter.nc", "summary.json", "flutter_summary.txt",
                                               "vg_1.png", "gaf.nc", "modes.nc",
                                               "participation.nc"}


def test_participation_concatenates_sweeps_and_keeps_empty_ones(plain, modes):
    """Two sweeps: the points carry their sweep's index in ``case``; a sweep without crossings
    adds none; no crossing at all gives a flutter_point of length 0."""
    _, res = plain
    lab, sweep = res["results"][0]
    empty = sweep.isel(crossing=slice(0, 0))
    both = flutter_participation([(lab, empty), (lab, sweep), (lab, sweep)], modes,
                                 configuration="c")
    assert list(both.case.values) == [1, 2] and list(both.flutter_mode.values) == [1, 1]
    np.testing.assert_array_equal(both.participation.values[0], both.participation.values[1])
    none = flutter_participation([(lab, empty)], modes)
    assert none.sizes["flutter_point"] == 0 and none.sizes["mode"] == 10
    assert none.attrs["units"] == "model units"


def test_structural_damping_raises_the_flutter_speed(plain, damped):
    """g = 0.03 on every mode (modal viscous, as Nastran's KDAMP = 1) delays flutter: measured
    395.1 -> 442.7 m/s (+12 %); asserted above +5 %."""
    v0 = _flutter(plain[1])[0]["velocity"]
    v3 = _flutter(damped)[0]["velocity"]
    assert v3 > 1.05 * v0


def test_case_damping_equals_the_deck_route_with_a_constant_table(modes, damped, tmp_path):
    """The case's structural_damping = 0.03 gives the crossings that the deck's own SDAMP selecting
    a TABDMP1 of constant g = 0.03 gives (the independent route through the cards)."""
    deck = deck_copy(tmp_path, lambda text: text.replace(
        "METHOD = 401\n", "METHOD = 401\nSDAMP = 2001\n").replace(
        "+TAB100,0.,0.01,100.,0.005,ENDT", "+TAB100,0.,0.03,100.,0.03,ENDT"))
    (req,) = read_flutter_requests(read_pynastran(deck), str(deck), [502])
    assert req.damping.kind == "viscous" and req.damping.table_g == (0.03, 0.03)
    (fmethod,) = read_flutter_requests(read_pynastran(deck), str(deck))  # subcase 1's FMETHOD 501
    assert fmethod.sid == 501 and fmethod.damping == req.damping
    via_deck = _chain(deck, modes)
    assert len(via_deck["summary"]) == len(damped["summary"]) >= 1
    for a, b in zip(via_deck["summary"], damped["summary"]):
        assert (a["kind"], a["root"]) == (b["kind"], b["root"])
        assert a["velocity"] == pytest.approx(b["velocity"], rel=1e-10)
        assert a["frequency"] == pytest.approx(b["frequency"], rel=1e-10)
    # and the case's value replaces the deck's table
    (over,) = read_flutter_requests(read_pynastran(deck), str(deck), [502], 0.01)
    assert over.damping == StructuralDamping(g=0.01, kind="viscous")


def test_flutter_id_override_keeps_its_subcase_sdamp(tmp_path):
    """A FLUTTER id asked for by [flutter] flutter_ids gets the SDAMP of the subcase whose FMETHOD
    names it (Nastran's pairing); an id no FMETHOD names gets the global SDAMP (none here)."""
    deck = deck_copy(tmp_path, lambda text: text.replace(
        "  FMETHOD = 501\n", "  FMETHOD = 501\n  SDAMP = 2001\n"))
    bdf = read_pynastran(deck)
    (fmethod,) = read_flutter_requests(bdf, str(deck))
    (asked,) = read_flutter_requests(bdf, str(deck), [501])
    # TABDMP1 2001 of the deck: g = 0.01 at 0 Hz, 0.005 at 100 Hz (TYPE G)
    assert fmethod.damping == asked.damping == StructuralDamping(
        frequency=(0.0, 100.0), table_g=(0.01, 0.005), kind="viscous")
    (other,) = read_flutter_requests(bdf, str(deck), [502])
    assert other.damping == StructuralDamping()


def test_kdamp_minus_one_is_refused(tmp_path):
    deck = deck_copy(tmp_path, lambda text: text.replace("PARAM,LMODES,10",
                                                          "PARAM,LMODES,10\nPARAM,KDAMP,-1"))
    with pytest.raises(UnsupportedCardError, match="KDAMP.*Fix: remove PARAM KDAMP"):
        read_flutter_requests(read_pynastran(deck), str(deck), [502])


@pytest.mark.filterwarnings("ignore::UserWarning", "ignore::RuntimeWarning")
def test_pipeline_flutter_case_agrees_with_the_library(tmp_path, capsys, plain):
    """``pipeline flutter CASE`` runs configuration_modes + case_flutter with the case's
    structural damping and [selection] rigid_hz: same crossings and participation as the library
    calls, and the damping is applied (the crossing moves from the undamped one)."""
    case_file = tmp_path / "case.toml"
    case_file.write_text(
        f'name = "chain"\nunits = "si"\n[[configurations]]\nname = "baseline"\n'
        f'deck = "{DECK.as_posix()}"\nnmodes = 10\n[flutter]\nflutter_ids = [502]\n'
        'structural_damping = 0.01\n[selection]\nrigid_hz = 0.1\n')
    assert main(["flutter", str(case_file), "--out", str(tmp_path / "fl")]) == 0
    capsys.readouterr()
    case = read_case(case_file)
    config = case.configurations[0]
    lib = case_flutter(case, config, configuration_modes(config)[0])
    cli_summary = json.loads((tmp_path / "fl" / "baseline" / "summary.json").read_text())
    assert len(cli_summary) == len(lib["summary"]) >= 1
    for a, b in zip(cli_summary, lib["summary"]):
        assert (a["kind"], a["root"], a["mach"]) == (b["kind"], b["root"], b["mach"])
        assert a["velocity"] == pytest.approx(b["velocity"], rel=1e-9)
        assert a["frequency"] == pytest.approx(b["frequency"], rel=1e-9)
    part = read_dataset(tmp_path / "fl" / "baseline" / "participation.nc")
    np.testing.assert_allclose(part.participation.values, lib["participation"].participation.values,
                               rtol=1e-9, atol=1e-9)
    assert part.attrs["configuration"] == "baseline" and part.attrs["rigid_hz"] == 0.1
    v_damped = _flutter(lib)[0]["velocity"]
    assert v_damped > _flutter(plain[1])[0]["velocity"] * 1.001


@pytest.mark.filterwarnings("ignore::UserWarning", "ignore::RuntimeWarning")
def test_pipeline_flutter_deck_agrees_with_the_library(tmp_path, capsys, plain):
    """``pipeline flutter DECK`` (deck_modes + flutter_chain): the library's crossings and
    participation, labelled "model units" (a bare deck)."""
    out = tmp_path / "fl"
    assert main(["flutter", str(DECK), "--flutter-id", "502", "--out", str(out)]) == 0
    capsys.readouterr()
    _, lib = plain
    summary = json.loads((out / "summary.json").read_text())
    assert [(c["kind"], c["root"]) for c in summary] == [(c["kind"], c["root"])
                                                         for c in lib["summary"]]
    for a, b in zip(summary, lib["summary"]):
        assert a["velocity"] == pytest.approx(b["velocity"], rel=1e-9)
        assert a["frequency"] == pytest.approx(b["frequency"], rel=1e-9)
    part = read_dataset(out / "participation.nc")
    np.testing.assert_allclose(part.participation.values,
                               lib["participation"].participation.values, rtol=1e-9, atol=1e-9)
    assert part.attrs["units"] == "model units" and part.attrs["configuration"] == "bah_plane"


@pytest.mark.filterwarnings("ignore::UserWarning", "ignore::RuntimeWarning")
def test_case_solver_runs_the_g_and_p_methods(tmp_path, capsys, plain):
    """``[flutter] solver = "g"``: the FLUTTER 502 points are solved by the g-method (method "G" in
    summary.json and flutter.nc), and its elastic flutter point is Nastran's (394.0 m/s, 3.18 Hz,
    F06) and p-k's within 1 % (all exact at g = 0); ``solvers = { 502 = "p" }`` likewise with the
    p-method on the rational fit (method "P-RFA")."""
    base = (f'name = "chain"\nunits = "si"\n[[configurations]]\nname = "baseline"\n'
            f'deck = "{DECK.as_posix()}"\nnmodes = 10\n[flutter]\nflutter_ids = [502]\n')
    for i, extra in enumerate(('solver = "g"\n', 'solvers = { 502 = "p" }\n')):
        case_file = tmp_path / f"case{i}.toml"
        case_file.write_text(base + extra)
        assert main(["flutter", str(case_file), "--out", str(tmp_path / f"fl{i}")]) == 0
        capsys.readouterr()
        summary = json.loads((tmp_path / f"fl{i}" / "baseline" / "summary.json").read_text())
        flutter = [c for c in summary if is_flutter(c["kind"])]
        method = ("G", "P-RFA")[i]
        assert {c["method"] for c in summary} == {method}
        assert flutter[0]["velocity"] == pytest.approx(394.0, rel=0.02)
        assert flutter[0]["frequency"] == pytest.approx(3.18, rel=0.02)
        assert flutter[0]["velocity"] == pytest.approx(_flutter(plain[1])[0]["velocity"], rel=0.01)
        ds = read_dataset(tmp_path / f"fl{i}" / "baseline" / "flutter.nc")
        assert ds["method"].values.tolist() == [method]


@pytest.mark.parametrize("extra, message", [
    ('solver = "q"\n', f"solver = 'q'; valid: {', '.join(sorted(SOLVERS))}."),
    ('solvers = { 501 = "g" }\n', "names FLUTTER [501], which are not run"),
])
def test_case_solver_errors(tmp_path, capsys, extra, message):
    """An unknown solver names the valid ones; a per-id solver for a FLUTTER card that is not run
    names the card and the ones that are."""
    case_file = tmp_path / "case.toml"
    case_file.write_text(f'name = "chain"\nunits = "si"\n[[configurations]]\nname = "baseline"\n'
                         f'deck = "{DECK.as_posix()}"\nnmodes = 10\n[flutter]\n'
                         f'flutter_ids = [502]\n{extra}')
    assert main(["flutter", str(case_file), "--out", str(tmp_path / "fl")]) != 0
    assert message in capsys.readouterr().err
