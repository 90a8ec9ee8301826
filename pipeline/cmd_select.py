"""``pipeline select [CASE.toml] [--thresholds 0.85,0.9,0.95] [--out DIR]``: the mode-selection study.

Brings the baseline stages of the run folder up to date (the same stages as ``pipeline run``), then
tabulates, for every threshold, Mach number, configuration and critical flutter root, the modes
needed to reach the threshold (pipeline.selection.selection_study) and writes
``selection_study/study.nc``, ``study.txt`` and ``study.png`` into the run folder.
"""
from __future__ import annotations

import argparse


def _thresholds(text: str) -> tuple:
    """argparse type of --thresholds: comma-separated fractions in (0, 1]."""
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a comma-separated list of numbers; "
                                         "give e.g. 0.85,0.9,0.95") from None
    if not values or not all(0.0 < v <= 1.0 for v in values):
        raise argparse.ArgumentTypeError(f"{text!r}: every threshold must be in (0, 1], e.g. "
                                         "0.85,0.9,0.95")
    return tuple(sorted(set(values)))


def add_parser(sub) -> None:
    p = sub.add_parser("select", help="mode-selection study: modes needed per participation "
                                      "threshold, Mach, configuration and flutter root")
    p.add_argument("case", nargs="?", default=None, help="TOML case file (default: shipped example)")
    p.add_argument("--thresholds", type=_thresholds, default=(0.85, 0.90, 0.95, 0.98),
                   help="participation thresholds (default 0.85,0.9,0.95,0.98)")
    p.add_argument("--out", default=None, help="run folder (default: runs/<case name>)")
    p.set_defaults(func=run)


def run(args) -> int:
    from pipeline.cmd_run import case_and_run_folder
    from pipeline.run import run_case
    from pipeline.selection import selection_study, study_table
    from pipeline.selection_plots import plot_selection_study
    from structures.common.errors import InputError
    from structures.common.files import read_dataset, staged_folder, write_dataset, write_text

    case, out = case_and_run_folder(args)
    if case.flutter is None:
        raise InputError(f"file {case.path}: no [flutter] section, so there are no flutter roots "
                         "to select modes for. Fix: add [flutter] with the FLUTTER ids.")
    run_case(case, out, baseline_only=True)
    parts = {c.name: read_dataset(out / f"stage0/{c.name}/flutter/participation.nc")
             for c in case.configurations}
    study = selection_study(parts, args.thresholds)
    table = study_table(study)
    with staged_folder(out / "selection_study") as staged:
        write_dataset(study, staged / "study.nc")
        write_text(table + "\n", staged / "study.txt")
        plot_selection_study(study).savefig(staged / "study.png", dpi=120)
    print(table)
    print(f"study written to {out / 'selection_study'}")
    return 0
