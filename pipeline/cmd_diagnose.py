"""``pipeline diagnose CASE.toml [--json FILE] [--out DIR]``: name the effect the model is missing.

Runs the ``diagnose`` stage of the case (pipeline.stages.diagnose_plan: with flutter, stage 0's
grid GAFs, modes and flutter first) in the run folder of ``pipeline run`` (``--out``, default
``runs/<case name>``): ``diagnose/diagnose.json``, ``diagnose.nc``, ``<config>_calibrated.bdf``
and ``<config>_diagnosed.bdf`` (the models of the gap before and after; with a suspension
identified from the test's suspension modes, ``<config>_as_tested.bdf`` adds it), ``*.png``
(pipeline.diagnose.outputs). Prints the verdict, each named effect with its location
and parameters, the best five candidates and the gap before -> after; ``--json FILE`` also writes
the verdict record there. The case and its ``[diagnose]`` table, every deck and GVT file and the
output paths are checked, and the diagnosis's data checks made
(pipeline.diagnose.inputs.check_case_data, in pipeline.run.run_case), before anything is
computed.
"""
from __future__ import annotations

import json
from pathlib import Path


def add_parser(sub) -> None:
    p = sub.add_parser("diagnose", help="name the physical effect the model is missing (lumped "
                                        "mass, flexible joint, taper, curvature, boundary "
                                        "stiffness), add it and show the gap shrink")
    p.add_argument("case", help="TOML case file (the same as pipeline run's)")
    p.add_argument("--json", default=None, metavar="FILE",
                   help="also write the verdict record (diagnose.json) to this file")
    p.add_argument("--out", default=None, help="run folder (default: runs/<case name>)")
    p.set_defaults(func=run)


def run(args) -> int:
    from pipeline.cmd_run import case_and_run_folder
    from pipeline.diagnose.outputs import FOLDER, verdict_summary
    from pipeline.run import run_case
    from structures.common.files import check_output, write_json
    from structures.units import unit_labels

    case, out = case_and_run_folder(args)
    if args.json:
        check_output(args.json, folder=False, option="--json")
    check_output(out, folder=True)
    run_case(case, out, diagnose_only=True)
    record = json.loads((out / FOLDER / "diagnose.json").read_text())
    print(verdict_summary(record, unit_labels(case.units).velocity))
    print(f"\ndiagnosis written to {out / FOLDER}")
    if args.json:
        write_json(record, Path(args.json))
        print(f"verdict record written to {args.json}")
    return 0
