"""Pipeline benchmark: the README's ``pipeline run`` of a case, end to end, in a fresh folder.

The command (``python -m pipeline.cli run [CASE]``, what the ``pipeline`` console script runs)
starts in a new temporary folder, so the run folder ``runs/<case name>/`` is empty and every stage
computes. Figures, one ``key: value`` per line:

- ``stage_s[NAME]``: the seconds of each stage's compute, as its manifest entry records them
  (``manifest.json`` ``seconds``), in the order the stages ran;
- ``stages_total_s``: their sum; ``wall_s``: the command's wall time, start-up included;
  ``outside_stages_s``: the difference (interpreter and imports, case and deck checks, hashing
  and renaming the outputs, the manifest);
- ``cpu_s``: user + system seconds of the command (all its threads), less sensitive than wall
  time to other load on the shared machine;
- ``peak_rss_mb``: the command's peak resident memory (``resource.getrusage(RUSAGE_CHILDREN)``
  ``ru_maxrss``; the only child this script waits for);
- ``load_average_1min_before`` / ``_after``: what else was running.

Usage: ``PYTHONPATH=. python benchmarks/pipeline.py [CASE.toml] [--keep DIR]``
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run_pipeline(case: Path | None, folder: Path) -> tuple[float, Path]:
    """``pipeline run [CASE]`` in ``folder``; returns its wall seconds and its run folder."""
    cmd = [sys.executable, "-m", "pipeline.cli", "run"] + ([str(case)] if case else [])
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    log = folder / "pipeline_run.log"
    start = time.perf_counter()
    with open(log, "w") as out:
        code = subprocess.run(cmd, cwd=folder, env=env, stdout=out,
                              stderr=subprocess.STDOUT).returncode
    wall = time.perf_counter() - start
    if code != 0:
        raise SystemExit(f"pipeline run failed with exit code {code}:\n"
                         f"{log.read_text(errors='replace')[-3000:]}")
    (manifest,) = (folder / "runs").glob("*/manifest.json")
    return wall, manifest.parent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case", nargs="?", type=Path, default=None,
                        help="TOML case file (default: the shipped example)")
    parser.add_argument("--keep", type=Path, default=None,
                        help="copy the run folder and the command's log here afterwards")
    args = parser.parse_args()
    case = args.case.resolve() if args.case else None
    print(f"case: {case or 'shipped example'}")
    print(f"cpu_count: {os.cpu_count()}")
    print(f"load_average_1min_before: {os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory(prefix="pipeline_bench_") as tmp:
        wall, run_dir = run_pipeline(case, Path(tmp))
        usage = resource.getrusage(resource.RUSAGE_CHILDREN)
        manifest = json.loads((run_dir / "manifest.json").read_text())
        if args.keep:
            shutil.copytree(tmp, args.keep, dirs_exist_ok=True)
    total = 0.0
    for name, entry in manifest.items():
        print(f"stage_s[{name}]: {entry['seconds']:.3f}")
        total += entry["seconds"]
    print(f"stages: {len(manifest)}")
    print(f"stages_total_s: {total:.3f}")
    print(f"wall_s: {wall:.3f}")
    print(f"outside_stages_s: {wall - total:.3f}")
    print(f"cpu_s: {usage.ru_utime + usage.ru_stime:.3f}")
    print(f"peak_rss_mb: {usage.ru_maxrss / 1024.0:.0f}")
    print(f"load_average_1min_after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
