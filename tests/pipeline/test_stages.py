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
from structures.common.errors import InputError
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
        "solver": replace(case, flutter=replace(f, solver=_other(("pk", "g"), f.solver))),
        "solvers": replace(case, flutter=replace(f, solvers={502: "g"})),
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


def test_configurations_share_grid_gafs_only_on_one_aerodynamic_grid(case, tmp_path):
    """The example's two configurations (one airframe, two mass loadings) share one grid-GAF
    stage; a configuration whose aerodynamic grid differs (one more chordwise box row) gets its
    own, and its flutter stages read that one."""
    names = [s.name for s in stage_plan(case, 0) if s.name.startswith("stage0/aero/")]
    assert names == ["stage0/aero/baseline"]
    assert "stage0/aero/baseline" in _stage(case, "stage1/flutter/fuel").after
    example = CASE.parent
    for path in example.iterdir():
        if path.is_file():
            (tmp_path / path.name).write_bytes(path.read_bytes())
    fuel = (tmp_path / "bah_plane_fuel.bdf").read_text()
    aero = (tmp_path / "aero_bah.inc").read_text()
    (tmp_path / "aero_fuel.inc").write_text(aero)
    (tmp_path / "bah_plane_fuel.bdf").write_text(fuel.replace("aero_bah.inc", "aero_fuel.inc"))
    same = read_case(tmp_path / "case.toml")
    assert [s.name for s in stage_plan(same, 0) if "/aero/" in s.name] == ["stage0/aero/baseline"]
    lines = aero.splitlines()
    caero = next(i for i, line in enumerate(lines) if line.startswith("CAERO1"))
    fields = lines[caero].split(",")                           # free field: CAERO1,EID,PID,CP,
    fields[5] = str(int(fields[5]) + 1)                        # NSPAN,NCHORD: one more box row
    lines[caero] = ",".join(fields)
    (tmp_path / "aero_fuel.inc").write_text("\n".join(lines) + "\n")
    other = read_case(tmp_path / "case.toml")
    plan = stage_plan(other, 0)
    assert [s.name for s in plan if "/aero/" in s.name] == ["stage0/aero/baseline",
                                                            "stage0/aero/fuel"]
    assert "stage0/aero/fuel" in next(s for s in plan if s.name == "stage0/flutter/fuel").after


def test_tuning_starts_from_the_model_the_diagnosis_ended_with(case, tmp_path):
    """With [diagnose] before_tuning, stage 1's tuning runs after the diagnosis and every tuning
    stage starts from its decks: the diagnosed deck of a configuration with a named effect, the
    calibrated one of a configuration without; without before_tuning, from the case's decks."""
    from pipeline.diagnose.inputs import diagnose_case_settings
    from pipeline.graph import Stage, StageContext
    from pipeline.stages import _start_decks

    early = replace(case, diagnose=diagnose_case_settings(
        {"before_tuning": True}, CASE, case.configurations, True))
    for n in (1, 2):
        assert "diagnose" in next(s for s in stage_plan(early, n) if s.name.endswith("tuning")).after
        assert "diagnose" not in next(s for s in stage_plan(case, n)
                                      if s.name.endswith("tuning")).after
    ctx = StageContext(Stage("stage1/tuning", print), tmp_path / "staging", tmp_path)
    assert _start_decks(ctx, case) == {c.name: c.deck for c in case.configurations}
    first, second = (c.name for c in case.configurations)
    folder = tmp_path / "diagnose"
    folder.mkdir()
    written = [folder / f"{name}.bdf" for name in (f"{first}_calibrated", f"{second}_calibrated",
                                                   f"{second}_diagnosed")]
    for path in written:
        path.write_text("BEGIN BULK\nENDDATA\n")
    ctx.upstream["diagnose"] = written
    assert _start_decks(ctx, early) == {first: folder / f"{first}_calibrated.bdf",
                                        second: folder / f"{second}_diagnosed.bdf"}
    ctx.upstream["diagnose"] = written[1:]       # a manifest without the first's deck
    with pytest.raises(InputError, match=f"{first}_calibrated.bdf.*--from diagnose"):
        _start_decks(ctx, early)
