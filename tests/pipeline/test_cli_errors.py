"""Every bad input of issue 10 through ``pipeline.cli.main``: one ``error:`` line naming the file /
card / key and the fix, exit code 2 (130 for Ctrl-C), never a traceback, no output left behind.
``pipeline flutter CASE`` and ``pipeline run CASE`` give the same flutter crossings."""
from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest

from flutter.results import is_flutter
from tests.pipeline.cli_run import cli

DATA = Path(__file__).resolve().parents[1] / "data"
ROOT = Path(__file__).resolve().parents[2]
BAH = ("bah_plane.bdf", "structure_bah.inc", "aero_bah.inc", "interface_bah.inc")


def failed(argv, capsys, *needles, code=2) -> str:
    """Assert a clean failure: exit code, no traceback, the needles and a fix in stderr."""
    got, out, err = cli(argv, capsys)
    assert got == code, (got, out, err)
    assert "Traceback" not in err + out
    for needle in needles:
        assert needle in err, (needle, err)
    assert "Fix" in err or "valid" in err or "must be" in err, err
    return err


def listing(folder: Path) -> set:
    return {p.relative_to(folder) for p in folder.rglob("*")}


@pytest.fixture()
def pt145(tmp_path) -> Path:
    lines = (DATA / "pt145" / "pt145.bdf").read_text().splitlines(keepends=True)
    (tmp_path / "pt145.bdf").write_text("".join(lines))
    return tmp_path / "pt145.bdf"


def _deck_with(pt145: Path, name: str, edit) -> Path:
    lines = pt145.read_text().splitlines(keepends=True)
    path = pt145.parent / name
    path.write_text("".join(edit(lines)))
    return path


def _cbar5(lines) -> int:
    return next(i for i, line in enumerate(lines) if line.startswith("CBAR    5 "))


# ---------------------------------------------------------------------------- decks (issue list 1)
def test_missing_deck(tmp_path, capsys):
    failed(["flutter", tmp_path / "nope.bdf"], capsys, "nope.bdf", "no such deck")


def test_empty_file(tmp_path, capsys):
    (tmp_path / "empty.bdf").write_text("")
    failed(["flutter", tmp_path / "empty.bdf"], capsys, "empty.bdf", "the deck is empty")


def test_truncated_card(pt145, capsys):
    deck = _deck_with(pt145, "cut.bdf",
                      lambda ls: ls[:_cbar5(ls)] + [ls[_cbar5(ls)][:30] + "\n"] + ls[_cbar5(ls) + 1:])
    failed(["flutter", deck], capsys, "cut.bdf", "CBAR", "pyNastran could not read")


def test_garbage_line(pt145, capsys):
    deck = _deck_with(pt145, "garbage.bdf",
                      lambda ls: ls[:_cbar5(ls)] + ["GARBAGE LINE %%% 12 ,, ;;\n"] + ls[_cbar5(ls):])
    failed(["flutter", deck], capsys, "garbage.bdf", "GARBAGE")


def test_undefined_grid(pt145, capsys):
    deck = _deck_with(pt145, "undefined.bdf", lambda ls: [
        ln.replace("CBAR    10      1       10      11 ", "CBAR    10      1       10      999")
        for ln in ls])
    failed(["flutter", deck], capsys, "undefined.bdf", "card CBAR 10", "grid 999")


def test_undefined_spline_grid(tmp_path, capsys):
    for name in BAH:
        shutil.copy(DATA / "bah_plane" / name, tmp_path / name)
    inc = tmp_path / "structure_bah.inc"
    inc.write_text(inc.read_text().replace("SET1,1002,18,19,20", "SET1,1002,18,19,20,777"))
    failed(["flutter", tmp_path / "bah_plane.bdf"], capsys, "bah_plane.bdf", "SPLINE2 802",
           "[777]")


def test_op2_given_as_a_deck(tmp_path, capsys):
    shutil.copy(DATA / "bah_plane" / "bah_plane.op2", tmp_path / "results.bdf")
    failed(["flutter", tmp_path / "results.bdf"], capsys, "results.bdf", "binary file")


def test_deck_without_grids(tmp_path, capsys):
    (tmp_path / "nogrid.bdf").write_text("SOL 103\nCEND\nBEGIN BULK\nPARAM,WTMASS,1.0\nENDDATA\n")
    failed(["modes", tmp_path / "nogrid.bdf"], capsys, "nogrid.bdf", "no grids")


# ----------------------------------------------------------------- options (issue list 4)
@pytest.mark.parametrize("value", ["0", "-3", "ten"])
@pytest.mark.parametrize("command", ["modes", "flutter"])
def test_nmodes_must_be_a_positive_count(command, value, pt145, capsys):
    code, _, err = cli([command, pt145, "--nmodes", value], capsys)
    assert code == 2 and "Traceback" not in err
    assert "--nmodes" in err and (">= 1" in err)


def test_out_existing_file_where_a_folder_is_needed(pt145, tmp_path, capsys):
    (tmp_path / "taken").write_text("mine")
    failed(["flutter", pt145, "--out", tmp_path / "taken"], capsys, "--out", "taken",
           "a folder is needed")
    assert (tmp_path / "taken").read_text() == "mine"


def test_out_folder_where_a_file_is_needed(pt145, tmp_path, capsys):
    (tmp_path / "folder").mkdir()
    failed(["modes", pt145, "--out", tmp_path / "folder"], capsys, "--out", "a file is needed")


def test_out_below_a_file(pt145, tmp_path, capsys):
    (tmp_path / "plain").write_text("")
    failed(["flutter", pt145, "--out", tmp_path / "plain" / "sub"], capsys, "is a file, not a folder")


def test_out_unwritable_folder(pt145, tmp_path, capsys, monkeypatch):
    locked = tmp_path / "locked"
    locked.mkdir()
    real = os.access
    # root may write anywhere, so the permission answer is simulated for this one folder
    monkeypatch.setattr(os, "access", lambda p, mode: False if Path(p) == locked else real(p, mode))
    failed(["modes", pt145, "--out", locked / "modes.nc"], capsys, "is not writable")
    assert listing(locked) == set()


# ------------------------------------------------------------------ case files (issue list 2)
def _case(tmp_path, text: str, gvt: bool = False) -> Path:
    for name in BAH:
        shutil.copy(DATA / "bah_plane" / name, tmp_path / name)
    if gvt:
        shutil.copy(ROOT / "data" / "bah_wing" / "gvt.unv", tmp_path / "gvt.unv")
    path = tmp_path / "case.toml"
    path.write_text(text)
    return path


BASE = 'name = "bah"\n[[configurations]]\nname = "baseline"\ndeck = "bah_plane.bdf"\n'


@pytest.mark.parametrize("extra, needles", [
    ('nmodes = "ten"\n', ["nmodes = 'ten' is a string; expected an integer"]),
    ("nmodes = 10.5\n", ["nmodes = 10.5 is a number; expected an integer"]),
    ("nmodes = true\n", ["nmodes = True is a boolean; expected an integer"]),
    ("nmodes = 0\n", ["nmodes = 0 must be >= 1"]),
    ("measured_mass = 19177.9\n", ["measured_mass = 19177.9 is a number; expected a table"]),
    ("mass = 3\n", ["mass = 3 is an integer; expected a string"]),
    ('gvt = "missing.unv"\n', ["gvt 'missing.unv'", "does not exist"]),
    ('[flutter]\nflutter_ids = 502\n', ["[flutter]", "flutter_ids = 502 is an integer; "
                                        "expected a list of integers", "flutter_ids = [502]"]),
    ('[flutter]\nflutter_ids = "502"\n', ["flutter_ids = '502' is a string; expected a list"]),
    ('[flutter]\nkernel = "cubic"\n', ["kernel = 'cubic'; valid: quartic, parabolic"]),
])
def test_case_value_types(tmp_path, capsys, extra, needles):
    case = _case(tmp_path, BASE + extra)
    before = listing(tmp_path)
    err = failed(["run", case, "--out", tmp_path / "run"], capsys, "case.toml", *needles)
    assert "configurations" in err or "[flutter]" in err
    assert listing(tmp_path) == before  # nothing computed, nothing written


def test_case_flutter_id_missing_from_the_deck_before_any_stage(tmp_path, capsys):
    case = _case(tmp_path, BASE + 'gvt = "gvt.unv"\n[flutter]\nflutter_ids = [999]\n', gvt=True)
    before = listing(tmp_path)
    for argv in (["run", case, "--out", tmp_path / "run"], ["flutter", case, "--out", tmp_path / "fl"]):
        failed(argv, capsys, "bah_plane.bdf", "[flutter] flutter_ids", "FLUTTER 999",
               "which is not defined", "Fix")
        assert listing(tmp_path) == before  # no stage ran, nothing written


def test_case_unit_system_lists_the_valid_ones(tmp_path, capsys):
    case = _case(tmp_path, 'units = "imperial"\n' + BASE)
    failed(["run", case, "--out", tmp_path / "run"], capsys, "units = 'imperial'",
           "si, english_in, english_ft")
    assert not (tmp_path / "run").exists()


def test_case_name_must_be_a_string(tmp_path, capsys):
    case = _case(tmp_path, "name = 7\n" + BASE.split("\n", 1)[1])
    failed(["run", case, "--out", tmp_path / "run"], capsys, "case.toml",
           "name = 7 is an integer; expected a string")
    case.write_text(BASE.replace('name = "baseline"', "name = 7"))
    failed(["flutter", case], capsys, "[[configurations]] #1", "name = 7 is an integer")


def test_tuning_maxiter_type(tmp_path, capsys):
    case = _case(tmp_path, BASE + 'gvt = "gvt.unv"\n[tuning]\nmaxiter = "three"\n', gvt=True)
    failed(["tune", case], capsys, "case.toml", "[tuning]",
           "maxiter = 'three' is a string; expected an integer")
    failed(["run", case, "--out", tmp_path / "run"], capsys, "maxiter = 'three'")
    assert not (tmp_path / "run").exists() and not (tmp_path / "bah_tuning").exists()


@pytest.mark.parametrize("tuning, needles", [
    ('[[tuning.objective]]\nindex = 3\n', ["[[tuning.objective]] #1", "index = 3 is an integer"]),
    ('[[tuning.objective]]\nindex = "*"\nweight = "big"\n', ["weight = 'big' is a string"]),
    ('[[tuning.constraints]]\nindex = "*"\n', ["[[tuning.constraints]] #1", "'limit' is required"]),
    ('[[tuning.variables]]\nname = "I1"\nfields = [["PBAR", "11", "I1"]]\n',
     ["[[tuning.variables]] #1", "is not [card, id, field]"]),
    ('method = "newton"\n', ["[tuning]", "method = 'newton'; valid: slsqp"]),
    ('restart = "old/history.nc"\n', ["restart history 'old/history.nc'", "does not exist"]),
    ('[tuning.configurations.cruise]\ntest_modes = [7]\n', ["names no configuration; valid"]),
])
def test_tuning_section_is_validated_at_read(tmp_path, capsys, tuning, needles):
    head = "[tuning]\n" if not tuning.startswith(("[[", "[tuning.")) else "[tuning]\nmaxiter = 5\n"
    case = _case(tmp_path, BASE + 'gvt = "gvt.unv"\n' + head + tuning, gvt=True)
    failed(["tune", case], capsys, "case.toml", *needles)
    failed(["run", case, "--out", tmp_path / "run"], capsys, "case.toml", *needles)
    assert not (tmp_path / "run").exists()


def test_missing_gvt_is_found_before_the_modes_stage(tmp_path, capsys):
    case = _case(tmp_path, BASE + 'gvt = "gvt.unv"\n')
    failed(["run", case, "--out", tmp_path / "run"], capsys, "gvt 'gvt.unv'", "does not exist")
    assert not (tmp_path / "run").exists()


def test_bad_deck_in_a_case_leaves_no_run_folder(tmp_path, capsys):
    case = _case(tmp_path, BASE)
    (tmp_path / "bah_plane.bdf").write_text("")
    failed(["run", case, "--out", tmp_path / "new" / "run"], capsys, "bah_plane.bdf", "empty")
    assert not (tmp_path / "new").exists()


def test_failed_flutter_of_a_case_writes_nothing(tmp_path, capsys, pt145):
    deck = _deck_with(pt145, "undefined.bdf", lambda ls: [
        ln.replace("CBAR    10      1       10      11 ", "CBAR    10      1       10      999")
        for ln in ls])
    case = tmp_path / "two.toml"
    case.write_text('name = "two"\n[[configurations]]\nname = "good"\ndeck = "pt145.bdf"\n'
                    f'nmodes = 4\n[[configurations]]\nname = "bad"\ndeck = "{deck.name}"\n')
    failed(["flutter", case, "--out", tmp_path / "out" / "flutter"], capsys, "undefined.bdf")
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------------------------ Ctrl-C
def test_interrupt_names_the_stage_and_keeps_finished_ones(tmp_path, capsys, monkeypatch):
    import pipeline.chain

    case = _case(tmp_path, BASE + "nmodes = 6\n")

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(pipeline.chain, "configuration_modes", interrupted)
    code, out, err = cli(["run", case, "--out", tmp_path / "run"], capsys)
    assert code == 130
    assert err.strip().splitlines() == [
        "interrupted in stage0/modes/baseline; run the same command again to resume"]
    assert not (tmp_path / "run").exists()  # nothing finished, nothing kept


def test_interrupt_outside_a_stage_names_the_command(pt145, capsys, monkeypatch):
    import pipeline.cmd_modes

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(pipeline.cmd_modes, "assemble", interrupted)
    code, _, err = cli(["modes", pt145], capsys)
    assert code == 130 and err == "interrupted in modes; run the same command again to resume\n"


# ------------------------------------------------------------ flutter CASE == run CASE
@pytest.mark.filterwarnings("ignore::UserWarning", "ignore::RuntimeWarning")
def test_flutter_of_a_case_agrees_with_run(tmp_path, capsys):
    case = ROOT / "data" / "bah_wing" / "case.toml"
    code, _, err = cli(["flutter", case, "--out", tmp_path / "fl"], capsys)
    assert code == 0, err
    code, _, err = cli(["run", case, "--out", tmp_path / "run"], capsys)
    assert code == 0, err
    cli_crossings = json.loads((tmp_path / "fl" / "baseline" / "summary.json").read_text())
    run_crossings = json.loads((tmp_path / "run" / "stage0" / "baseline" / "flutter" /
                                   "summary.json").read_text())
    assert len(cli_crossings) == len(run_crossings) >= 1
    for a, b in zip(cli_crossings, run_crossings):
        assert (a["kind"], a["root"], a["mach"]) == (b["kind"], b["root"], b["mach"])
        # the same library calls on the same modes: equal to rounding
        assert a["velocity"] == pytest.approx(b["velocity"], rel=1e-9)
        assert a["frequency"] == pytest.approx(b["frequency"], rel=1e-9)
    flutter = [c for c in cli_crossings if is_flutter(c["kind"])]
    # the case's FLUTTER 502 (Nastran: 394.0 m/s), not the deck's FMETHOD 501
    assert len(flutter) == 1 and flutter[0]["velocity"] == pytest.approx(394.0, rel=0.02)


# ------------------------------------------------------------------ damaged result and GVT files
def test_damaged_netcdf_and_cut_gvt_through_correlate(pt145, tmp_path, capsys):
    (tmp_path / "modes.nc").write_text("not netCDF")
    gvt = ROOT / "data" / "bah_wing" / "gvt.unv"
    failed(["correlate", tmp_path / "modes.nc", gvt], capsys, "modes.nc",
           "not a readable netCDF4 file")
    data = gvt.read_bytes()
    (tmp_path / "cut.unv").write_bytes(data[:len(data) // 2])
    failed(["correlate", pt145, tmp_path / "cut.unv", "--out", tmp_path / "corr.nc", "--figures",
            tmp_path / "figures"], capsys, "cut.unv", "no closing -1")
    assert not (tmp_path / "corr.nc").exists() and not (tmp_path / "figures").exists()


def test_damaged_run_manifest(tmp_path, capsys):
    case = _case(tmp_path, BASE)
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "manifest.json").write_text("{ half")
    failed(["run", case, "--out", tmp_path / "run"], capsys, "manifest.json",
           "the run manifest is damaged")


# ------------------------------------------------------------------ INCLUDE files
@pytest.mark.parametrize("edit, needles", [
    (lambda folder: (folder / "aero_bah.inc").unlink(),
     ["bah_plane.bdf", "INCLUDE names 'aero_bah.inc', which does not exist"]),
    (lambda folder: (folder / "structure_bah.inc").write_text(
        (DATA / "bah_plane" / "structure_bah.inc").read_text() + "\nINCLUDE 'bah_plane.bdf'\n"),
     ["structure_bah.inc", "bah_plane.bdf -> structure_bah.inc -> bah_plane.bdf"]),
])
def test_include_missing_or_circular(tmp_path, capsys, monkeypatch, edit, needles):
    """Named before pyNastran reads: it would dump pyNastran_crash.bdf into the current folder."""
    deck_dir, work = tmp_path / "deck", tmp_path / "work"
    work.mkdir()
    deck_dir.mkdir()
    for name in BAH:
        shutil.copy(DATA / "bah_plane" / name, deck_dir / name)
    edit(deck_dir)
    monkeypatch.chdir(work)
    for argv in (["modes", deck_dir / "bah_plane.bdf"], ["flutter", deck_dir / "bah_plane.bdf"],
                 ["check", deck_dir / "bah_plane.bdf"]):
        failed(argv, capsys, *needles)
        assert listing(work) == set()


def test_absurd_thru_range_refused_before_pynastran(pt145, capsys):
    """pyNastran expands SET1 ... THRU 99999999 into 1e8 ids (minutes, > 5 GB) before failing."""
    deck = _deck_with(pt145, "thru.bdf", lambda lines: [
        ln if not ln.startswith("SET1") else "SET1    1001    1       THRU    99999999\n"
        for ln in lines])
    failed(["modes", deck], capsys, "thru.bdf", "1 THRU 99999999", "99,999,999 ids")


def test_include_name_swallowing_the_deck(tmp_path, capsys, monkeypatch):
    """An unclosed quote makes the INCLUDE name run on over the following lines."""
    deck = tmp_path / "open_quote.bdf"
    deck.write_text("SOL 103\nCEND\nBEGIN BULK\nINCLUDE 'geometry\n" + "GRID,1,,0.,0.,0.\n" * 60 +
                    "ENDDATA\n")
    monkeypatch.chdir(tmp_path)
    failed(["modes", deck], capsys, "open_quote.bdf", "line 4: INCLUDE names", "...")
    assert listing(tmp_path) == {Path("open_quote.bdf")}


def test_pynastran_message_that_cannot_be_formatted(pt145, capsys):
    """pyNastran's own message about a card holding inf raises ValueError when formatted."""
    deck = _deck_with(pt145, "inf.bdf", lambda lines: [
        ln if not ln.startswith("SPLINE2 100") else
        "SPLINE2 0       101     101     124     100     inf     1.0     1       +SP\n"
        for ln in lines])
    failed(["flutter", deck], capsys, "inf.bdf", "pyNastran could not read the deck")
