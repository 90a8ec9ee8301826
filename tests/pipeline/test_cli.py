"""The ``pipeline`` command: modes, run (shipped example, resume) and case-file validation."""
from __future__ import annotations

import json
import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from flutter.results import is_flutter
from pipeline.case import read_case
from pipeline.cli import main
from structures.common.errors import InputError
from structures.modes import read_modes
from structures.common.files import read_dataset
from tests.structures.spring_decks import spring_chain

DATA = Path(__file__).resolve().parents[1] / "data"
BAH_CASE = Path(__file__).resolve().parents[2] / "data" / "bah_wing" / "case.toml"


def test_modes_command_prints_table_and_writes_contract(tmp_path, capsys):
    out = tmp_path / "modes.nc"
    assert main(["modes", str(DATA / "pt145" / "pt145.bdf"), "--nmodes", "4", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "39.9615" in text and "mass" in text and "x_cg" in text
    ds = read_modes(out)
    assert list(ds["mode"].values) == [1, 2, 3, 4]
    assert ds["frequency"].attrs["units"] == "Hz"
    assert ds["shape"].dims == ("mode", "dof")
    assert set(np.unique(ds["component"].values)) == set(range(1, 7))
    assert ds.attrs["source"] == "our solver"


def test_modes_command_says_when_the_model_has_fewer_modes_than_asked(tmp_path, capsys):
    """The deck's EIGRL asks for 5 modes; one of its 3 DOFs carries mass: one mode, and a note."""
    deck = spring_chain(tmp_path / "chain.bdf", 5)
    out = tmp_path / "modes.nc"
    assert main(["modes", str(deck), "--out", str(out)]) == 0
    assert "note: 5 modes were asked for; the model has 1, as many as its degrees of freedom " \
        "that carry mass." in capsys.readouterr().out
    ds = read_modes(out)
    assert ds.sizes["mode"] == 1 and ds.attrs["modes_requested"] == 5


def test_a_closed_stdout_ends_quietly(tmp_path):
    """``pipeline modes deck | head -1``: the reader closes the pipe before the tables are
    written; the command exits with 1 and no traceback."""
    deck = spring_chain(tmp_path / "chain.bdf", 5)
    program = "import sys; from pipeline.cli import main; sys.exit(main())"
    proc = subprocess.Popen([sys.executable, "-c", program, "modes", str(deck)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            cwd=Path(__file__).resolve().parents[2])
    proc.stdout.close()
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 1
    assert "Traceback" not in err and "BrokenPipe" not in err, err


@pytest.mark.filterwarnings("ignore::UserWarning", "ignore::RuntimeWarning")
def test_run_bah_example_then_resume(tmp_path, capsys):
    out = tmp_path / "run"
    base = out / "stage0" / "baseline"
    assert main(["run", str(BAH_CASE), "--out", str(out)]) == 0
    assert (out / "report.html").exists() and (base / "modes.nc").exists()
    assert "[stage0/modes/baseline] 10 modes" in capsys.readouterr().out
    assert main(["run", str(BAH_CASE), "--out", str(out)]) == 0
    assert "[stage0/modes/baseline] up to date, skipped" in capsys.readouterr().out
    (base / "modes.nc").unlink()  # a lost output is redone
    with warnings.catch_warnings():
        warnings.simplefilter("always")   # the test's marks ignore UserWarning
        assert main(["run", str(BAH_CASE), "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert "output stage0/baseline/modes.nc is missing or damaged; recomputing" in captured.err
    assert "[stage0/modes/baseline] 10 modes" in captured.out
    freq = read_modes(base / "modes.nc")["frequency"].values
    assert freq[2] == pytest.approx(2.454016, rel=1e-5)
    mass = read_dataset(base / "mass_properties.nc")
    assert float(mass["mass"]) == pytest.approx(18947.36, rel=1e-12)
    # The example's FLUTTER 502 (PK, Mach 0.2): Nastran's F06 has flutter at 394.0 m/s, 3.18 Hz.
    summary = json.loads((base / "flutter" / "summary.json").read_text())
    flutter = [c for c in summary if is_flutter(c["kind"])]
    assert len(flutter) == 1
    assert flutter[0]["velocity"] == pytest.approx(394.0, rel=0.02)
    assert flutter[0]["frequency"] == pytest.approx(3.18, rel=0.03)
    # The example's synthetic GVT: six test modes paired, errors from the truth model's changes.
    corr = read_dataset(base / "correlation.nc")
    assert corr.sizes["test_mode"] == 6 and not corr["interchanged"].values.any()
    assert np.all(np.abs(corr["frequency_error"].values) < 10.0)
    assert float(corr["mass_relative_error"].sel(quantity="weight")) == pytest.approx(
        100 * (18947.36 / 19177.9 - 1), abs=1e-3)
    report = (out / "report.html").read_text()
    assert 'id="flutter-change"' in report


def test_case_file_unknown_key_lists_valid_ones(tmp_path):
    (tmp_path / "m.bdf").write_text((DATA / "pt145" / "pt145.bdf").read_text())
    case = tmp_path / "case.toml"
    case.write_text('name = "x"\n[[configurations]]\nname = "a"\ndeck = "m.bdf"\nnmode = 3\n')
    with pytest.raises(InputError, match=r"unknown keys \['nmode'\]; valid: .*'nmodes'"):
        read_case(case)
    case.write_text('name = "x"\nunits = "imperial"\n[[configurations]]\nname = "a"\ndeck = "m.bdf"\n')
    with pytest.raises(InputError, match="valid: si, english_in, english_ft"):
        read_case(case)


@pytest.mark.parametrize("index", ["empty:frequency:*", "baseline:frequencies:*", "frequency:3",
                                   "baseline:frequency"])
def test_tuning_index_patterns_checked_before_any_run(tmp_path, index):
    """A [tuning] index that can name no index of the case fails when the case is read, not at the
    first tuning stage after the baseline analyses."""
    example = Path(__file__).resolve().parents[2] / "data" / "bah_wing"
    text = (example / "case.toml").read_text().replace('index = "*:mass:weight"',
                                                       f'index = "{index}"')
    for path in example.iterdir():
        if path.is_file():
            (tmp_path / path.name).write_bytes(path.read_bytes())
    (tmp_path / "case.toml").write_text(text)
    with pytest.raises(InputError, match=r"\[\[tuning.constraints\]\] #1: index = "
                                         + re.escape(f"'{index}'")
                                         + r" names no index of this case.*'baseline', 'fuel'"):
        read_case(tmp_path / "case.toml")
    (tmp_path / "case.toml").write_text(text.replace(f'index = "{index}"', 'index = "f*:mass:*"'))
    assert read_case(tmp_path / "case.toml").tuning.constraints[0] == ("f*:mass:*", 1e-4)
