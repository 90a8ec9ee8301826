"""pipeline.stages: every case setting and file a stage's compute reads is in its declaration.

A setting a compute reads but the stage does not declare is a silent-staleness bug (the stage
stays "done" after the setting changed). Reference: the list of what each compute reads, taken
from the code of pipeline.chain / pipeline.loop / pipeline.report (the table in pipeline.stages'
docstring); for each entry, changing that one setting of the shipped example's case must change
the stage's declared settings or files. Nothing is computed.
"""
from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from pipeline.case import read_case
from pipeline.graph import file_hash
from pipeline.stages import final_stages, stage_plan
from structures.common.nastran import deck_files
from structures.sensitivity import SHAPE_METHODS
from structures.tuning import METHODS

CASE = Path(__file__).resolve().parents[2] / "data" / "bah_wing" / "case.toml"


@pytest.fixture(scope="module")
def case():
    return read_case(CASE)


def _stage(case, name: str):
    stages = stage_plan(case, 0) + stage_plan(case, 1) + final_stages(case, 1, [])
    return next(s for s in stages if s.name == name)


def _declared(case, name: str) -> str:
    """What the graph's fingerprint of stage ``name`` hashes, but the upstream outputs: its
    settings, its files' names and contents, the names of its upstream stages."""
    stage = _stage(case, name)
    files = [[Path(f).name, file_hash(Path(f))] for f in stage.files]
    return json.dumps([stage.settings, files, list(stage.after)], sort_keys=True, default=str)


def _other(options, value):
    return next(o for o in options if o != value)


def _config(case, **changes):
    first = replace(case.configurations[0], **changes)
    return replace(case, configurations=(first, *case.configurations[1:]))


def _changes(case) -> dict:
    """stage -> {what changed: the case with that one change}."""
    f, s, t, loop = case.flutter, case.selection, case.tuning, case.loop
    moved = replace(t.variables[0], lower=0.5, upper=1.5)
    tuning = {
        "variables": replace(t, variables=(moved, *t.variables[1:])),
        "objective": replace(t, objective=t.objective + (("*:mac:*", 0.5),)),
        "constraints": replace(t, constraints=t.constraints + (("*:mass:weight", 2e-4),)),
        "method": replace(t, method=_other(METHODS, t.method)),
        "maxiter": replace(t, maxiter=t.maxiter + 1),
        "shape_method": replace(t, shape_method=_other(SHAPE_METHODS, t.shape_method)),
        "allowed_violation": replace(t, allowed_violation=t.allowed_violation + 0.01),
        "per_configuration": replace(t, per_configuration=(
            (case.configurations[0].name, {"mass_targets": {"weight": 1.0}}),)),
    }
    flutter = {
        "kernel": replace(case, flutter=replace(f, kernel=_other(("quartic", "parabolic"),
                                                                   f.kernel))),
        "flutter_ids": replace(case, flutter=replace(f, flutter_ids=(501,))),
        "structural_damping": replace(case, flutter=replace(f, structural_damping=0.02)),
        "rigid_hz": replace(case, selection=replace(s, rigid_hz=s.rigid_hz * 2)),
        "units": replace(case, units=_other(("si", "english_in"), case.units)),
    }
    return {
        "stage0/modes/baseline": {"nmodes": _config(case, nmodes=12),
                                  "mass": _config(case, mass=_other(("lumped", "consistent"),
                                                                    case.configurations[0].mass))},
        "stage0/correlation/baseline": {
            "measured_mass": _config(case, measured_mass={"weight": 1.0}),
            "gvt": _config(case, gvt=case.configurations[1].gvt)},
        "stage0/flutter/baseline": flutter,
        "stage1/flutter/baseline": flutter,
        "stage0/selection": {
            "primary": replace(case, selection=replace(s, primary=s.primary - 0.01)),
            "secondary": replace(case, selection=replace(s, secondary=1.0)),
            "flutter_modes": replace(case, selection=replace(s, flutter_modes=3)),
            "loop standard": replace(case, loop=replace(loop, standard="NASA-STD-5002")),
            "loop stages": replace(case, loop=replace(loop, stages=loop.stages + 1))},
        "stage1/tuning": {
            **{key: replace(case, tuning=value) for key, value in tuning.items()},
            "loop standard": replace(case, loop=replace(loop, standard="NASA-STD-5002")),
            "nmodes": _config(case, nmodes=12),
            "mass": _config(case, mass="lumped"),
            "measured_mass": _config(case, measured_mass={"weight": 1.0}),
            "gvt": _config(case, gvt=case.configurations[1].gvt)},
        "report": {
            "name": replace(case, name="other"),
            "units": replace(case, units=_other(("si", "english_in"), case.units)),
            "envelope": replace(case, flutter=replace(f, envelope=None)),
            "deck named in the overview": _config(case, deck=case.configurations[1].deck),
            "loop stages": replace(case, loop=replace(loop, stages=loop.stages + 1))},
    }


def test_every_setting_a_stage_reads_is_declared(case):
    undeclared = [(stage, what) for stage, changes in _changes(case).items()
                  for what, changed in changes.items()
                  if _declared(changed, stage) == _declared(case, stage)]
    assert undeclared == []


def test_stages_reading_decks_declare_their_include_files(case):
    config = case.configurations[0]
    includes = set(deck_files(config.deck))
    assert len(includes) > 1   # the example's deck INCLUDEs its structure and aero
    for name in ("stage0/modes/baseline", "stage0/flutter/baseline", "stage1/tuning"):
        assert includes <= set(_stage(case, name).files), name
    assert config.gvt in _stage(case, "stage1/tuning").files
    # stage n >= 1 analyses read the tuned deck, an output of stage n's tuning
    for name in ("stage1/modes/baseline", "stage1/flutter/baseline"):
        assert "stage1/tuning" in _stage(case, name).after, name
