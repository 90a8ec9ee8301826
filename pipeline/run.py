"""``pipeline run``: a case's stages on the stage graph, the tuning <-> flutter loop, the report.

Stage 0 (baseline) computes modes, correlation, flutter and the mode selection of every
configuration; while the primary-mode targets are missed and ``[loop] stages`` allows, stage n
tunes the decks (objective and constraints from stage n-1's selection, pipeline.loop) and repeats
the analyses on the tuned decks. The flutter-change table and the report close the run. The
stages are declared in pipeline.stages; pipeline.graph decides what is up to date, so an
interrupted or changed run recomputes exactly what is missing or depends on the change.

A failed or interrupted run keeps the outputs of its finished stages; a run folder this run
created is removed when no stage finished.
"""
from __future__ import annotations

import shutil
from pathlib import Path

from pipeline.graph import Graph, source_version
from pipeline.progress import Display
from pipeline.stage import running
from pipeline.stages import (case_aero_groups, diagnose_plan, final_stages, possible_stage_names,
                             read_targets, stage_plan)
from structures.common.files import check_output

EXAMPLE_CASE = Path(__file__).resolve().parents[1] / "data" / "x56_like" / "case.toml"
#: The packages whose code computes the stages (their sources version every fingerprint).
PACKAGES = ("structures", "aero", "flutter", "pipeline")


def _walk(case, graph: Graph, display: Display, execute: bool, baseline_only: bool = False,
          diagnose_only: bool = False) -> int:
    """Register (and with ``execute`` bring up to date) the stages of the run in order; returns
    the last loop stage. Without ``execute`` a stage n + 1 is listed only when stage n's targets
    are known (its selection done) to be missed. ``baseline_only``: stage 0 and nothing else;
    ``diagnose_only``: the stages of pipeline.stages.diagnose_plan and nothing else."""
    baseline_only = baseline_only or diagnose_only
    last = case.loop.stages if case.loop is not None and not baseline_only else 0
    names, n = [], 0
    aero = case_aero_groups(case)
    while True:
        plan = diagnose_plan(case, display, aero) if diagnose_only else stage_plan(case, n,
                                                                                  display, aero)
        for stage in plan:
            graph.add(stage)
            names.append(stage.name)
            if execute:
                with running(stage.name), display.stage(stage.name):
                    graph.run(stage.name)
        if n >= last:
            break
        if not execute:
            done = {name for name, status, _ in graph.status() if status == "done"}
            if f"stage{n}/selection" not in done:
                break
        targets = read_targets(graph.dir, n)
        if targets is None or targets["met"]:
            break
        n += 1
    for stage in [] if baseline_only else final_stages(case, n, names, aero, display):
        graph.add(stage)
        if execute:
            with running(stage.name), display.stage(stage.name):
                graph.run(stage.name)
    return n


def run_case(case, out_dir, log=None, from_stage: str | None = None,
             baseline_only: bool = False, diagnose_only: bool = False) -> Path:
    """Bring every stage of ``case`` up to date in ``out_dir``; returns the report's path.

    Parameters
    ----------
    case : pipeline.case.Case
    out_dir : path
        The run folder.
    log : callable(str), optional
        Receives the log lines (default: printed, with a live progress line on a terminal).
    from_stage : str, optional
        Rerun this stage (a name, a prefix such as ``stage1`` or a glob) and everything after it.
    baseline_only : bool
        Bring stage 0 up to date and stop (``pipeline select``); returns the run folder.
    diagnose_only : bool
        Bring the ``diagnose`` stage and the stage-0 stages it reads up to date and stop
        (``pipeline diagnose``); returns the run folder.

    Raises
    ------
    InputError
        Before any stage runs: a flutter request the decks cannot meet, a measured CG outside
        its deck (:func:`pipeline.chain.check_case_masses`), a GVT file that does not read or
        has no shapes where the correlation runs (:func:`pipeline.chain.check_case_gvts`) and,
        when the diagnosis is among the stages, any data check of it
        (:func:`pipeline.diagnose.inputs.check_case_data`).
    """
    from pipeline.chain import check_case_gvts, check_case_masses, check_flutter_requests
    from pipeline.diagnose.inputs import check_case_data

    check_flutter_requests(case)
    check_case_masses(case)
    if not diagnose_only:
        check_case_gvts(case)        # the correlation and tuning stages need the test's shapes
    out = check_output(out_dir, folder=True)
    if diagnose_only or (case.diagnose is not None and not baseline_only):
        check_case_data(case)        # every deck and GVT file read, and checked with the model
    created = [p for p in (out, *out.parents) if not p.exists()]
    out.mkdir(parents=True, exist_ok=True)
    display = Display()
    if log is not None:
        display.log = log
    graph = Graph(out, log=display.log, code=source_version(*PACKAGES))
    if from_stage is not None:
        graph.force(from_stage, valid=possible_stage_names(case))
    graph.clean_staging()
    try:
        _walk(case, graph, display, execute=True, baseline_only=baseline_only,
              diagnose_only=diagnose_only)
    except BaseException:
        if not graph.manifest:   # nothing finished: leave no folder this run created
            for folder in created:
                if folder == out:
                    shutil.rmtree(out, ignore_errors=True)
                elif folder.is_dir() and not any(folder.iterdir()):
                    folder.rmdir()
        raise
    if baseline_only or diagnose_only:
        return out
    report = out / "report.html"
    display.log(f"report: {report}")
    return report


def run_status(case, out_dir) -> list[tuple[str, str, str]]:
    """(stage, status, reason) of every stage of ``case`` known from ``out_dir`` (done / stale /
    missing; nothing is computed)."""
    graph = Graph(Path(out_dir), log=lambda line: None, code=source_version(*PACKAGES))
    _walk(case, graph, Display(live=False), execute=False)
    return graph.status()
