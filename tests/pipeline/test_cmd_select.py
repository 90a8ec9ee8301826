"""``pipeline select`` (the mode-selection study) and ``pipeline status`` on the BAH example."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pipeline.cli import main
from structures.common.files import read_dataset

BAH_CASE = Path(__file__).resolve().parents[2] / "data" / "bah_wing" / "case.toml"


@pytest.mark.filterwarnings("ignore::UserWarning", "ignore::RuntimeWarning")
def test_select_study_on_the_example(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["select", str(BAH_CASE), "--out", str(out),
                 "--thresholds", "0.97,0.85,0.9"]) == 0
    printed = capsys.readouterr().out
    study = read_dataset(out / "selection_study" / "study.nc")
    assert study["threshold"].values.tolist() == [0.85, 0.9, 0.97]     # sorted
    assert set(study["configuration"].values) == {"baseline", "fuel"}
    n = study["n_modes"].values
    assert np.all(np.diff(n, axis=0) >= 0)            # more participation needs no fewer modes
    # Each configuration's one critical root (FLUTTER 502) is W1B with the rigid modes up to
    # 95.4 % (baseline) and 96.5 % (fuel) (stage0/selection.txt): W1B alone below 97 %, W1T
    # added at 97 %.
    assert study["primary_modes"].sel(threshold=0.9).values.tolist() == ["3", "3"]
    assert study["primary_modes"].sel(threshold=0.97).values.tolist() == ["3, 4", "3, 4"]
    assert (out / "selection_study" / "study.png").stat().st_size > 10_000
    assert "97%" in printed and (out / "selection_study" / "study.txt").read_text() in printed + "\n"
    # only the baseline stages ran
    assert (out / "stage0" / "selection.nc").exists() and not (out / "stage1").exists()
    assert not (out / "report.html").exists()


@pytest.mark.parametrize("text", ["0.9,x", "0,0.9", "1.2"])
def test_select_rejects_bad_thresholds(text, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["select", "--thresholds", text])
    assert exc.value.code == 2 and "--thresholds" in capsys.readouterr().err


@pytest.mark.filterwarnings("ignore::UserWarning", "ignore::RuntimeWarning")
def test_status_lists_done_stale_missing(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["status", str(BAH_CASE), "--out", str(out)]) == 0
    rows = {r.split()[0]: r.split()[1:3] for r in capsys.readouterr().out.splitlines()[1:]}
    assert rows["stage0/modes/baseline"] == ["missing", "never"]
    # one aerodynamic grid for both configurations: one grid-GAF stage
    assert [name for name in rows if name.startswith("stage0/aero/")] == ["stage0/aero/baseline"]
    assert main(["select", str(BAH_CASE), "--out", str(out)]) == 0    # the baseline stages only
    capsys.readouterr()
    assert main(["status", str(BAH_CASE), "--out", str(out)]) == 0
    status = {r.split()[0]: r.split()[1] for r in capsys.readouterr().out.splitlines()[1:]}
    assert all(status[s] == "done" for s in status if s.startswith("stage0/"))
    assert status["report"] == "missing" and status["flutter_change"] == "missing"
    # stage 0 misses the targets (fuel W1T +3.08 %), so stage 1 is listed, not yet computed
    assert status["stage1/tuning"] == "missing"
    (out / "stage0" / "fuel" / "correlation.nc").write_bytes(b"cut")
    assert main(["status", str(BAH_CASE), "--out", str(out)]) == 0
    rows = {r.split()[0]: " ".join(r.split()[1:]) for r in capsys.readouterr().out.splitlines()[1:]}
    assert rows["stage0/correlation/fuel"] == (
        "stale output stage0/fuel/correlation.nc is missing or damaged")
    assert rows["stage0/selection"] == "stale upstream stage0/correlation/fuel is not done"
    assert rows["stage0/flutter/fuel"] == "done"
