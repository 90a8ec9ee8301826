"""``pipeline run`` on the stage graph, end to end with real physics (issue 11's must-show tests).

Every run works on a copy of the shipped example (data/bah_wing: two configurations, their GVTs,
flutter at Mach 0.2) in a temporary folder, through the ``pipeline`` command in a subprocess of
the same interpreter. The copy caps the tuning loop (``[loop] stages`` at 1, ``[tuning] maxiter``
at 2) so that the file's runtime stays modest whatever the shipped case asks for.

References: an uninterrupted run of the same case (the module's ``reference`` run; a resumed,
repaired or partly forced run must reproduce its netCDF values to 1e-12 relative and its JSON
files); the manifest's recorded fingerprints and file modification times (what was rerun and what
was not); the correlation's frequency error of the changed GVT mode by hand; ``pipeline flutter``
of the same case (its summary.json entries to 1e-10 relative).
"""
from __future__ import annotations

import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from flutter.results import is_flutter
from pipeline.cli import main
from pipeline.graph import MANIFEST, STAGING
from structures.common.files import read_dataset
from structures.gvt import load_gvt, write_uff

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "data" / "bah_wing"
CONFIGS = ("baseline", "fuel")
RTOL = 1e-12
#: GVT change: test mode 5 (W2T, paired with FE mode 7, neither primary nor secondary) 4 % stiffer
CHANGED_MODE, FACTOR = 5, 1.04


def _case_copy(folder: Path) -> Path:
    """Copy the shipped example to ``folder`` with the tuning loop capped; returns its case file."""
    shutil.copytree(DATA, folder, ignore=shutil.ignore_patterns("__pycache__", "*.py"))
    case = folder / "case.toml"
    text = re.sub(r"(?m)^maxiter\s*=\s*\d+", "maxiter = 2", case.read_text())
    case.write_text(re.sub(r"(?m)^stages\s*=\s*\d+", "stages = 1", text))
    return case


def _command(*args) -> list[str]:
    return [sys.executable, "-m", "pipeline.cli", *map(str, args)]


def _env() -> dict:
    return dict(os.environ, PYTHONPATH=str(ROOT))


def _pipeline(*args, cwd: Path) -> subprocess.CompletedProcess:
    """``pipeline ARGS`` in a subprocess; fails the test with its stderr unless it exits 0."""
    done = subprocess.run(_command(*args), cwd=cwd, env=_env(), capture_output=True, text=True,
                          timeout=900)
    assert done.returncode == 0, done.stderr
    return done


def _status(case: Path, run_dir: Path, capsys) -> str:
    """The output of ``pipeline status CASE --out RUN_DIR`` (in this process: it computes
    nothing)."""
    capsys.readouterr()
    assert main(["status", str(case), "--out", str(run_dir)]) == 0
    return capsys.readouterr().out


def _manifest(run_dir: Path) -> dict:
    return json.loads((run_dir / MANIFEST).read_text())


def _outputs(run_dir: Path) -> list[str]:
    return sorted(rel for entry in _manifest(run_dir).values() for rel in entry["outputs"])


def _mtimes(run_dir: Path, stages) -> dict[str, int]:
    manifest = _manifest(run_dir)
    return {rel: (run_dir / rel).stat().st_mtime_ns
            for s in stages for rel in manifest[s]["outputs"]}


def _copy_run(reference, name: str) -> Path:
    """A copy of the reference run folder (file contents and modification times kept)."""
    return Path(shutil.copytree(reference.dir, reference.root / name))


def _same_numbers(a: np.ndarray, b: np.ndarray, rtol: float, where: str) -> None:
    """``a`` equals ``b``: strings and integers exactly, floats / complex to ``rtol`` of the
    largest magnitude of ``b`` (NaN where ``b`` is NaN)."""
    assert a.shape == b.shape, where
    if b.dtype.kind not in "fc":
        assert np.array_equal(a, b), where
        return
    nan = np.isnan(b)
    assert np.array_equal(np.isnan(a), nan), where
    scale = np.max(np.abs(b[~nan]), initial=0.0)
    assert np.all(np.abs(a[~nan] - b[~nan]) <= rtol * scale), where


def _moved(attrs: dict, moves: tuple[str, str]) -> dict:
    """``attrs`` with the run folder ``moves[0]`` in string values read as ``moves[1]`` (a
    stage-n output names the tuned deck in its own run folder)."""
    return {k: v.replace(*moves) if isinstance(v, str) else v for k, v in attrs.items()}


def _same_dataset(path: Path, ref: Path, moves: tuple[str, str], rtol: float = RTOL) -> None:
    a, b = read_dataset(path), read_dataset(ref)
    assert _moved(a.attrs, moves) == b.attrs, path
    assert sorted(a.variables) == sorted(b.variables), path
    for name in b.variables:
        assert a[name].dims == b[name].dims, (path, name)
        assert _moved(a[name].attrs, moves) == b[name].attrs, (path, name)
        _same_numbers(a[name].values, b[name].values, rtol, f"{path}: {name}")


def _same_json(a, b, rtol: float, where: str) -> None:
    if isinstance(b, dict):
        assert isinstance(a, dict) and a.keys() == b.keys(), where
        for key in b:
            _same_json(a[key], b[key], rtol, f"{where}/{key}")
    elif isinstance(b, list):
        assert isinstance(a, list) and len(a) == len(b), where
        for k, (x, y) in enumerate(zip(a, b)):
            _same_json(x, y, rtol, f"{where}[{k}]")
    elif isinstance(b, float):
        assert isinstance(a, (int, float)), where
        assert a == pytest.approx(b, rel=rtol, abs=0.0, nan_ok=True), where
    else:
        assert a == b, where


def _assert_same_results(run_dir: Path, ref_dir: Path) -> None:
    """Every output of ``ref_dir``'s manifest is in ``run_dir``, netCDF and JSON files equal."""
    outputs = _outputs(ref_dir)
    assert _outputs(run_dir) == outputs
    assert any(rel.endswith(".nc") for rel in outputs) and any(rel.endswith(".json")
                                                               for rel in outputs)
    for rel in outputs:
        if rel.endswith(".nc"):
            _same_dataset(run_dir / rel, ref_dir / rel, (str(run_dir), str(ref_dir)))
        elif rel.endswith(".json"):
            _same_json(json.loads((run_dir / rel).read_text()),
                       json.loads((ref_dir / rel).read_text()), RTOL, rel)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """An uninterrupted ``pipeline run`` of the example's copy."""
    root = tmp_path_factory.mktemp("run_loop")
    case = _case_copy(root / "case")
    ref = root / "reference"
    done = _pipeline("run", case, "--out", ref, cwd=root)
    assert (ref / "report.html").is_file() and not (ref / STAGING).exists()
    return SimpleNamespace(root=root, case=case, dir=ref, log=done.stdout)


def test_reference_run_has_every_stage_of_the_contract(reference):
    manifest = _manifest(reference.dir)
    for c in CONFIGS:
        for stage in ("modes", "correlation", "flutter"):
            assert f"stage0/{stage}/{c}" in manifest
        assert f"stage0/{c}/flutter/participation.nc" in manifest[f"stage0/flutter/{c}"]["outputs"]
    assert {"stage0/selection", "flutter_change", "report"} <= set(manifest)
    # the example misses its primary-mode targets at stage 0: the loop tunes (capped at 1 stage)
    assert {"stage1/tuning", "stage1/selection"} <= set(manifest)
    assert not any(name.startswith("stage2/") for name in manifest)
    assert all(entry["seconds"] > 0.0 for entry in manifest.values())


def test_sigkill_in_the_middle_of_a_stage_then_rerun_equals_uninterrupted(reference, capsys):
    run_dir = reference.root / "killed"
    flutter_staging = run_dir / STAGING / "stage0" / "flutter"
    with open(reference.root / "killed.log", "w") as log:
        proc = subprocess.Popen(_command("run", reference.case, "--out", run_dir),
                                cwd=reference.root, env=_env(), stdout=log, stderr=log)
        deadline = time.monotonic() + 600.0
        try:
            # a flutter stage is writing its outputs into its staging folder
            while not any(files for _, _, files in os.walk(flutter_staging)):
                assert proc.poll() is None, "the run ended before a flutter stage was caught"
                assert time.monotonic() < deadline, "no flutter stage started within 600 s"
                time.sleep(0.002)
            os.kill(proc.pid, signal.SIGKILL)
        finally:
            proc.wait()
    assert proc.returncode == -signal.SIGKILL
    assert "report" not in _manifest(run_dir)
    status = _status(reference.case, run_dir, capsys)
    assert re.search(r"stage0/modes/baseline\s+done", status)
    assert re.search(r"report\s+missing\s+never computed", status)

    rerun = _pipeline("run", reference.case, "--out", run_dir, cwd=reference.root)
    assert "[stage0/modes/baseline] up to date, skipped" in rerun.stdout
    assert re.search(r"\[stage0/flutter/\w+\] \d+ flutter crossing", rerun.stdout)  # the killed one
    assert not (run_dir / STAGING).exists()
    _assert_same_results(run_dir, reference.dir)


def test_truncated_stage_file_is_detected_and_recomputed(reference, capsys):
    run_dir = _copy_run(reference, "truncated")
    modes = run_dir / "stage0" / "baseline" / "modes.nc"
    size = modes.stat().st_size
    with open(modes, "r+b") as fh:
        fh.truncate(size // 2)
    status = _status(reference.case, run_dir, capsys)
    assert re.search(r"stage0/modes/baseline\s+stale\s+output stage0/baseline/modes\.nc is "
                     r"missing or damaged", status)

    rerun = _pipeline("run", reference.case, "--out", run_dir, cwd=reference.root)
    assert (f"warning: {run_dir / MANIFEST}: stage stage0/modes/baseline: output "
            f"stage0/baseline/modes.nc is missing or damaged; recomputing it") in rerun.stderr
    assert re.search(r"\[stage0/modes/baseline\] 10 modes", rerun.stdout)
    assert modes.stat().st_size == size
    # the recomputed modes are byte for byte the reference's: nothing downstream reruns
    assert "[stage0/flutter/baseline] up to date, skipped" in rerun.stdout
    assert "[report] up to date, skipped" in rerun.stdout
    assert _manifest(run_dir)["stage0/modes/baseline"]["outputs"] == \
           _manifest(reference.dir)["stage0/modes/baseline"]["outputs"]
    _assert_same_results(run_dir, reference.dir)


def test_changed_gvt_reruns_correlation_and_after_but_not_the_modes(reference, capsys):
    case = _case_copy(reference.root / "case_gvt")
    gvt = load_gvt(case.parent / "gvt.unv")
    k = int(np.flatnonzero(gvt["mode"].values == CHANGED_MODE)[0])
    gvt["frequency"].values[k] *= FACTOR
    write_uff(gvt, case.parent / "gvt.unv")
    run_dir = _copy_run(reference, "gvt")
    before = _manifest(run_dir)
    kept = [f"stage0/modes/{c}" for c in CONFIGS] + [f"stage0/flutter/{c}" for c in CONFIGS] + \
        ["stage0/correlation/fuel", "stage0/aero/baseline"]
    mtimes = _mtimes(run_dir, kept)

    status = _status(case, run_dir, capsys)
    for name in kept:
        assert re.search(rf"(?m)^\s+{re.escape(name)}\s+done$", status), name
    assert re.search(r"stage0/correlation/baseline\s+stale\s+an input changed", status)
    assert re.search(r"stage0/selection\s+stale\s+upstream stage0/correlation/baseline is not "
                     r"done", status)
    assert re.search(r"report\s+stale", status)

    _pipeline("run", case, "--out", run_dir, cwd=reference.root)
    after = _manifest(run_dir)
    for name in kept:
        assert {k: v for k, v in after[name].items() if k != "seconds"} == \
               {k: v for k, v in before[name].items() if k != "seconds"}, name
    assert _mtimes(run_dir, kept) == mtimes
    rerun = [name for name in before if name not in kept]
    assert {"stage0/correlation/baseline", "stage0/selection", "stage1/tuning",
            "stage1/flutter/baseline", "flutter_change", "report"} <= set(rerun)
    for name in rerun:
        assert after[name]["fingerprint"] != before[name]["fingerprint"], name

    corr = read_dataset(run_dir / "stage0" / "baseline" / "correlation.nc")
    old = read_dataset(reference.dir / "stage0" / "baseline" / "correlation.nc")
    changed = {"test_mode": CHANGED_MODE}
    test_f = float(corr["test_frequency"].sel(changed))
    fe_f = float(corr["paired_fe_frequency"].sel(changed))
    # UFF 55 keeps 6 significant digits of a frequency
    assert test_f == pytest.approx(float(old["test_frequency"].sel(changed)) * FACTOR, rel=1e-5)
    assert float(corr["frequency_error"].sel(changed)) == \
           pytest.approx(100.0 * (fe_f - test_f) / test_f, rel=1e-12)
    others = corr["test_mode"].values != CHANGED_MODE
    np.testing.assert_allclose(corr["frequency_error"].values[others],
                               old["frequency_error"].values[others], rtol=1e-12)


def test_pipeline_flutter_and_pipeline_run_give_the_same_flutter_points(reference):
    out = reference.root / "flutter_only"
    _pipeline("flutter", reference.case, "--out", out, cwd=reference.root)
    for c in CONFIGS:
        alone = json.loads((out / c / "summary.json").read_text())
        in_run = json.loads((reference.dir / "stage0" / c / "flutter" / "summary.json").read_text())
        assert any(is_flutter(entry["kind"]) for entry in in_run), c
        _same_json(alone, in_run, 1e-10, f"{c}/summary.json")
        assert all(math.isfinite(entry["velocity"]) for entry in in_run)


def test_from_flutter_reruns_flutter_and_after_not_modes_or_correlation(reference):
    run_dir = _copy_run(reference, "from_flutter")
    # both configurations share the baseline's grid GAFs (one aerodynamic grid)
    kept = [f"stage0/{s}/{c}" for s in ("modes", "correlation") for c in CONFIGS] + \
        ["stage0/aero/baseline"]
    rerun = [name for name in _manifest(run_dir) if name not in kept]
    assert {f"stage0/flutter/{c}" for c in CONFIGS} | {"stage0/selection", "flutter_change",
                                                       "report"} <= set(rerun)
    kept_times, rerun_times = _mtimes(run_dir, kept), _mtimes(run_dir, rerun)

    done = _pipeline("run", reference.case, "--out", run_dir, "--from", "stage0/flutter",
                     cwd=reference.root)
    for name in kept:
        assert f"[{name}] up to date, skipped" in done.stdout
    assert _mtimes(run_dir, kept) == kept_times
    now = _mtimes(run_dir, rerun)
    assert all(now[rel] != rerun_times[rel] for rel in rerun_times)
    _assert_same_results(run_dir, reference.dir)
