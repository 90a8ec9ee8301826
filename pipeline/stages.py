"""The stages of a case, declared for the stage graph (pipeline.graph), and what each computes.

Stage n = 0 is the baseline; stages n >= 1 are the tuning stages of the loop (pipeline.loop). Per
stage n and configuration C, with the run-folder files of the contract in DESIGN.md / the README:

==========================  =======================================  ==============================
stage                       reads                                    writes
==========================  =======================================  ==============================
``stageN/tuning`` (N >= 1)  decks (the diagnosed ones with           ``stageN/tuning/history.nc``,
                            before_tuning), GVT files, [tuning],     ``report.txt``, ``C_tuned.bdf``
                            [loop], stage N-1's selection and tuning
``stageN/modes/C``          deck (stage 0) or ``C_tuned.bdf``        ``stageN/C/modes.nc``,
                                                                     ``mass_properties.nc``
``stageN/correlation/C``    modes, mass properties, GVT file         ``stageN/C/correlation.nc``,
                                                                     ``stageN/C/correlation/*.png``
``stage0/aero/C``           deck, [flutter]                          ``stage0/aero/C/grid_gaf.nc``
                            (one per distinct aerodynamic grid)
``stageN/flutter/C``        modes, deck, grid GAFs, [flutter],       ``stageN/C/flutter/*``
                            [selection]
``stageN/selection``        participation, correlation, [selection]  ``stageN/selection.nc``,
                            [loop]                                   ``selection.txt``,
                                                                     ``targets.json`` (with [loop])
``diagnose`` ([diagnose])   decks, GVT files, measured mass,         ``diagnose/diagnose.json``,
                            [diagnose]; stage 0's flutter and grid   ``diagnose.nc``, ``*.png``,
                            GAFs (flutter on); after stage 0 with    ``C_calibrated.bdf``,
                            before_tuning, else before the report    ``C_diagnosed.bdf``,
                                                                     ``C/flutter_before/*``,
                                                                     ``C/flutter/*``
``flutter_change``          every stage's participation              ``flutter_change.nc``
``report``                  the whole run folder                     ``report.html``
==========================  =======================================  ==============================

Adding a stage is one factory function here (a :class:`pipeline.graph.Stage` with its settings,
files and upstream stages) and one line in :func:`stage_plan` or :func:`final_stages`.
"""
from __future__ import annotations

import json
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from flutter.results import is_flutter
from pipeline.graph import Stage, StageContext
from structures.common.errors import InputError
from structures.common.files import read_dataset, write_dataset, write_json, write_text
from structures.common.nastran import deck_files
from structures.units import unit_labels


def _tuned_deck(n: int, config: str) -> str:
    return f"stage{n}/tuning/{config}_tuned.bdf"


def _deck(ctx: StageContext, config, n: int):
    """The configuration with the deck of stage ``n`` (its own deck, or the tuned one)."""
    return config if n == 0 else replace(config, deck=ctx.run_dir / _tuned_deck(n, config.name))


def _measured_mass(case) -> dict:
    """configuration -> the mass targets of tuning ([tuning.configurations] or measured_mass)."""
    extra = dict(case.tuning.per_configuration) if case.tuning else {}
    return {c.name: dict(extra.get(c.name, {}).get("mass_targets", c.measured_mass))
            for c in case.configurations}


# ------------------------------------------------------------------------------------ computes
def _modes(ctx: StageContext, config, n: int) -> None:
    from pipeline.chain import configuration_modes
    from structures.modes import write_modes

    modes, props = configuration_modes(_deck(ctx, config, n))
    write_modes(modes, ctx.output(f"stage{n}/{config.name}/modes.nc"))
    write_dataset(props.to_dataset(), ctx.output(f"stage{n}/{config.name}/mass_properties.nc"))
    return f"{modes.sizes['mode']} modes, {modes['frequency'].values[-1]:.4g} Hz highest"


def _correlation(ctx: StageContext, config, n: int) -> None:
    from pipeline.chain import configuration_correlation
    from structures.correlation_plots import save_correlation_figures
    from structures.massprops import MassProperties
    from structures.modes import read_modes

    folder = ctx.run_dir / f"stage{n}/{config.name}"
    props = MassProperties.from_dataset(read_dataset(folder / "mass_properties.nc"))
    corr = configuration_correlation(config, read_modes(folder / "modes.nc"), props)
    write_dataset(corr, ctx.output(f"stage{n}/{config.name}/correlation.nc"))
    save_correlation_figures(corr, ctx.output(f"stage{n}/{config.name}/correlation/x").parent)
    worst = float(np.nanmax(np.abs(corr["frequency_error"].values)))
    return (f"{corr.sizes['test_mode']} test modes paired, largest frequency error "
            f"{worst:.2f} %")


def _aero(ctx: StageContext, case, config, progress=None) -> None:
    from pipeline.chain import case_grid_gaf

    gaf = case_grid_gaf(case, config, progress=progress)
    write_dataset(gaf, ctx.output(f"stage0/aero/{config.name}/grid_gaf.nc"))
    return (f"grid GAFs on {gaf.sizes['gdof_i']} spline degrees of freedom, "
            f"{gaf.sizes['mach']} Mach x {gaf.sizes['k']} k")


def _flutter(ctx: StageContext, case, config, n: int, aero: str, progress=None) -> None:
    from pipeline.chain import case_flutter
    from structures.modes import read_modes

    modes = read_modes(ctx.run_dir / f"stage{n}/{config.name}/modes.nc")
    out = ctx.output(f"stage{n}/{config.name}/flutter/x").parent
    grid = read_dataset(ctx.run_dir / f"stage0/aero/{aero}/grid_gaf.nc")
    result = case_flutter(case, _deck(ctx, config, n), modes, out_dir=out, progress=progress,
                          grid_gaf=grid)
    flutter = [c for c in result["summary"] if is_flutter(c["kind"])]
    if not flutter:
        return "no flutter crossing"
    low = min(flutter, key=lambda c: c["velocity"])
    u = unit_labels(case.units)
    return (f"{len(flutter)} flutter crossing(s), lowest {low['velocity']:.5g} {u.velocity} at "
            f"{low['frequency']:.4g} Hz")


def _selection(ctx: StageContext, case, n: int) -> None:
    from pipeline.loop import evaluate_targets
    from pipeline.selection import select_modes, selection_table

    names = [c.name for c in case.configurations]
    parts = {c: read_dataset(ctx.run_dir / f"stage{n}/{c}/flutter/participation.nc") for c in names}
    corrs = {c.name: read_dataset(ctx.run_dir / f"stage{n}/{c.name}/correlation.nc")
             for c in case.configurations if c.gvt is not None}
    pairing = {c: {int(fe): int(t) for t, fe in zip(corr["test_mode"].values,
                                                     corr["paired_fe_mode"].values)}
               for c, corr in corrs.items()}
    s = case.selection
    selection = select_modes(parts, primary=s.primary, secondary=s.secondary,
                             flutter_modes=s.flutter_modes, pairing=pairing)
    write_dataset(selection, ctx.output(f"stage{n}/selection.nc"))
    write_text(selection_table(selection) + "\n", ctx.output(f"stage{n}/selection.txt"))
    if case.loop is not None and len(corrs) == len(names):
        targets = evaluate_targets(selection, corrs, case.loop.criteria, n, case.loop.stages)
        write_json(targets, ctx.output(f"stage{n}/targets.json"))
    roles = selection["role"].values.astype(str)
    note = (f"primary modes {_modes_by_config(selection, roles, 'primary')}, secondary "
            f"{_modes_by_config(selection, roles, 'secondary')}")
    if case.loop is not None and len(corrs) == len(names):
        note += ("; targets met" if targets["met"] else
                 f"; {len(targets['failing'])} primary-mode target(s) missed")
    return note


def _modes_by_config(selection, roles, role: str) -> str:
    modes = selection["mode"].values
    return "; ".join(f"{c}: {[int(m) for m in modes[roles[i] == role]]}"
                     for i, c in enumerate(selection["configuration"].values))


def _tuning(ctx: StageContext, case, n: int, progress=None) -> None:
    from pipeline.loop import loop_terms, relaxed_at_start, tuning_problem
    from structures.design import write_tuned_bdf
    from structures.tuning import best_from_history, best_iteration, tune
    from structures.tuning_report import tuning_report

    settings = case.tuning
    decks = _start_decks(ctx, case)
    names = [c.name for c in case.configurations]
    selection = read_dataset(ctx.run_dir / f"stage{n - 1}/selection.nc")
    objective, constraints, test_modes = loop_terms(selection, names, case.loop.criteria,
                                                    _measured_mass(case))
    prior = tuple(t for t in settings.objective if str(t[0]).startswith("design:"))
    problem = tuning_problem(case, objective + prior, constraints + settings.constraints,
                             test_modes, decks=decks)
    if n > 1:   # go on from the design the previous stage wrote out
        previous = read_dataset(ctx.run_dir / f"stage{n - 1}/tuning/history.nc")
        start = previous["design"].values[int(previous.attrs["chosen_iteration"])]
    elif settings.restart is not None:
        start = best_from_history(read_dataset(settings.restart), settings.allowed_violation)
    else:
        start = None
    problem, relaxed = relaxed_at_start(problem, start)
    result = tune(problem, method=settings.method, start=start, maxiter=settings.maxiter,
                  progress=progress)
    # the design written out: the restart rule's pick of the whole history (the optimiser's last
    # point when it converged feasibly; a better earlier one when maxiter cut it short)
    chosen = best_iteration(result.history, settings.allowed_violation)
    design = result.history["design"].values[chosen]
    history = result.history.assign_attrs(
        success=int(result.success), message=result.message, stage=n, chosen_iteration=chosen,
        objective_terms="; ".join(name for name, _ in objective),
        relaxed_constraints="; ".join(f"{name}: {eps:.4g} -> {new:.4g}"
                                      for name, eps, new in relaxed))
    write_dataset(history, ctx.output(f"stage{n}/tuning/history.nc"))
    write_text(tuning_report(history, after=chosen) + "\n",
               ctx.output(f"stage{n}/tuning/report.txt"))
    for c in case.configurations:
        write_tuned_bdf(decks[c.name], ctx.output(_tuned_deck(n, c.name)), result.space, design)
    return (f"{'converged' if result.success else 'not converged'} after {result.iterations} "
            f"iterations, objective {float(history['objective'].values[chosen]):.4e} "
            f"(evaluation {chosen}), "
            f"{len(objective)} objective terms, {len(problem.constraints)} constraints "
            f"({len(relaxed)} relaxed to the start design)")


def _flutter_change(ctx: StageContext, case, last: int) -> None:
    from pipeline.flutter_change import flutter_change

    stages = [{c.name: read_dataset(ctx.run_dir / f"stage{k}/{c.name}/flutter/participation.nc")
               for c in case.configurations} for k in range(last + 1)]
    write_dataset(flutter_change(stages), ctx.output("flutter_change.nc"))


def _diagnose(ctx: StageContext, case, aero: dict, progress=None) -> None:
    from pipeline.diagnose.outputs import write_diagnosis

    result = write_diagnosis(case, ctx.folder, ctx.run_dir, aero=aero, progress=progress)
    named = "; ".join(f"{e[0].kind} at {e[0].label}" for e in result.effects)
    return f"verdict {result.verdict}" + (f": {named}" if named else "")


def _report(ctx: StageContext, case) -> None:
    from pipeline.report import write_report

    return str(write_report(case, ctx.run_dir, out=ctx.output("report.html")).name)


# ------------------------------------------------------------------------------------ settings
def _flutter_settings(case) -> dict:
    f = case.flutter
    return {"kernel": f.kernel, "flutter_ids": list(f.flutter_ids),
            "structural_damping": f.structural_damping, "rigid_hz": case.selection.rigid_hz,
            "units": case.units, "matched": None if f.matched is None else repr(f.matched),
            "solver": f.solver, "solvers": [list(p) for p in f.solvers]}


def _tuning_settings(case) -> dict:
    t = case.tuning
    return {"variables": [repr(v) for v in t.variables], "objective": list(t.objective),
            "constraints": list(t.constraints), "method": t.method, "maxiter": t.maxiter,
            "shape_method": t.shape_method, "allowed_violation": t.allowed_violation,
            "per_configuration": [[name, sorted(dict(v).items())]
                                  for name, v in t.per_configuration],
            "standard": case.loop.standard,
            "configurations": [[c.name, c.nmodes, c.mass, sorted(c.measured_mass.items())]
                               for c in case.configurations]}


def diagnose_stage(case, aero: dict, display=None) -> Stage:
    """The ``diagnose`` stage (pipeline.diagnose.outputs): reads every configuration's deck, GVT
    file and measured mass, ``[diagnose]``, and with its flutter on ``[flutter]`` and stage 0's
    flutter and grid GAFs; writes ``diagnose/*``."""
    from pipeline.diagnose.inputs import case_diagnose_settings

    options = case_diagnose_settings(case)
    flutter = options.flutter and case.flutter is not None
    after = tuple(f"stage0/flutter/{c.name}" for c in case.configurations) if flutter else ()
    after += tuple(sorted({f"stage0/aero/{aero[c.name][0]}" for c in case.configurations})
                   if flutter else ())
    settings = {"diagnose": options.record(),
                "measured_mass": [[c.name, sorted(c.measured_mass.items())]
                                  for c in case.configurations],
                "flutter": _flutter_settings(case) if flutter else None}
    files = tuple(f for c in case.configurations for f in (*deck_files(c.deck), c.gvt))
    return Stage("diagnose", partial(_diagnose, case=case, aero=aero,
                                     progress=None if display is None else display.note),
                 settings=settings, files=files, after=after)


def _before_tuning(case) -> bool:
    return case.diagnose is not None and case.diagnose.before_tuning


def _start_decks(ctx: StageContext, case) -> dict:
    """configuration -> the deck every tuning stage starts from (its design applies to it): with
    ``before_tuning``, the model the diagnosis ended with (the named effects added to the
    calibrated deck, :func:`pipeline.diagnose.outputs.final_deck`, among the outputs of the
    ``diagnose`` stage, which every tuning stage then declares upstream), else the case's deck."""
    if not _before_tuning(case):
        return {c.name: c.deck for c in case.configurations}
    from pipeline.diagnose.outputs import final_deck

    outputs = {Path(p).resolve() for p in ctx.input("diagnose")}
    decks = {c.name: final_deck(ctx.run_dir, c.name) for c in case.configurations}
    missing = [str(d) for d in decks.values() if d.resolve() not in outputs]
    if missing:
        raise InputError(f"the diagnose stage of {ctx.run_dir} did not write {missing}, which the "
                         "tuning starts from ([diagnose] before_tuning). Fix: run the same "
                         "command again with --from diagnose.")
    return decks


# ------------------------------------------------------------------------------------ the plan
def case_aero_groups(case) -> dict:
    """pipeline.chain.aero_groups of a case with [flutter] ({} without): compute it once per run
    and give it to every :func:`stage_plan` (it parses every deck)."""
    from pipeline.chain import aero_groups

    return aero_groups(case) if case.flutter is not None else {}


def stage_plan(case, n: int, display=None, aero: dict | None = None) -> list[Stage]:
    """The stages of stage ``n`` (0: baseline; n >= 1: a tuning stage and its analyses);
    ``display`` (pipeline.progress.Display) is told the optimiser's iterations and the flutter
    requests; ``aero`` is :func:`case_aero_groups` (computed when not given)."""
    iteration = None if display is None else display.iteration
    note = None if display is None else display.note
    out = []
    aero = case_aero_groups(case) if aero is None else aero
    if n == 0:   # the grid GAFs, once per aerodynamic grid, serve every stage's modes
        for config in case.configurations:
            if config.name in aero and aero[config.name][0] == config.name:
                out.append(Stage(f"stage0/aero/{config.name}",
                                 partial(_aero, case=case, config=config, progress=note),
                                 settings={**_flutter_settings(case),
                                           "signature": aero[config.name][1]},
                                 files=tuple(deck_files(config.deck))))
    after_deck = ()
    if n >= 1:
        files = tuple(f for c in case.configurations for f in (*deck_files(c.deck), c.gvt))
        files += (case.tuning.restart,) if case.tuning.restart is not None and n == 1 else ()
        after = (f"stage{n - 1}/selection",) + ((f"stage{n - 1}/tuning",) if n > 1 else ())
        after += ("diagnose",) if _before_tuning(case) else ()
        out.append(Stage(f"stage{n}/tuning", partial(_tuning, case=case, n=n, progress=iteration),
                         settings=_tuning_settings(case), files=files, after=after))
        after_deck = (f"stage{n}/tuning",)
    for c in case.configurations:
        files = tuple(deck_files(c.deck)) if n == 0 else ()
        out.append(Stage(f"stage{n}/modes/{c.name}", partial(_modes, config=c, n=n),
                         settings={"nmodes": c.nmodes, "mass": c.mass}, files=files,
                         after=after_deck))
        if c.gvt is not None:
            out.append(Stage(f"stage{n}/correlation/{c.name}",
                             partial(_correlation, config=c, n=n),
                             settings={"measured_mass": sorted(c.measured_mass.items())},
                             files=(c.gvt,), after=(f"stage{n}/modes/{c.name}",)))
        if case.flutter is not None:
            out.append(Stage(f"stage{n}/flutter/{c.name}",
                             partial(_flutter, case=case, config=c, n=n,
                                     aero=aero[c.name][0], progress=note),
                             settings=_flutter_settings(case), files=files,
                             after=(f"stage{n}/modes/{c.name}",
                                    f"stage0/aero/{aero[c.name][0]}") + after_deck))
    if case.flutter is not None:
        after = tuple(s.name for s in out if "/flutter/" in s.name or "/correlation/" in s.name)
        settings = {"selection": [case.selection.primary, case.selection.secondary,
                                  case.selection.flutter_modes],
                    "loop": None if case.loop is None else [case.loop.stages, case.loop.standard]}
        out.append(Stage(f"stage{n}/selection", partial(_selection, case=case, n=n),
                         settings=settings, after=after))
    out += [diagnose_stage(case, aero, display)] if n == 0 and _before_tuning(case) else []
    return out


def diagnose_plan(case, display=None, aero: dict | None = None) -> list[Stage]:
    """The stages ``pipeline diagnose`` runs: stage 0's grid GAFs, modes and flutter when the
    diagnosis computes flutter speeds, then ``diagnose``."""
    aero = case_aero_groups(case) if aero is None else aero
    stage = diagnose_stage(case, aero, display)
    needed = {a for s in stage.after for a in (s, f"stage0/modes/{s.rsplit('/', 1)[-1]}")}
    return [s for s in stage_plan(case, 0, display, aero) if s.name in needed] + [stage]


def final_stages(case, last: int, upstream: list[str], aero: dict | None = None,
                 display=None) -> list[Stage]:
    """The diagnosis (``[diagnose]`` without before_tuning), the flutter-change table over stages
    0..``last`` and the report (after ``upstream``); ``aero`` as :func:`stage_plan`."""
    out = [] if case.diagnose is None or _before_tuning(case) else [
        diagnose_stage(case, case_aero_groups(case) if aero is None else aero, display)]
    if case.flutter is not None:
        after = tuple(f"stage{k}/flutter/{c.name}" for k in range(last + 1)
                      for c in case.configurations)
        out.append(Stage("flutter_change", partial(_flutter_change, case=case, last=last),
                         settings={"stages": last}, after=after))
    report_settings = {"name": case.name, "units": case.units,
                       "envelope": None if case.flutter is None or case.flutter.envelope is None
                       else [case.flutter.envelope.mach, case.flutter.envelope.velocity],
                       # the overview names each configuration's deck and GVT file
                       "configurations": [[c.name, str(c.deck), str(c.gvt)]
                                          for c in case.configurations],
                       "stages": None if case.loop is None else case.loop.stages}
    out.append(Stage("report", partial(_report, case=case), settings=report_settings,
                     after=tuple(upstream) + tuple(s.name for s in out)))
    return out


def read_targets(run_dir, n: int) -> dict | None:
    """Stage ``n``'s targets.json (None when the stage has none)."""
    path = run_dir / f"stage{n}/targets.json"
    return json.loads(path.read_text()) if path.is_file() else None


def possible_stage_names(case) -> list[str]:
    """Every stage a run of ``case`` may have (for ``--from``)."""
    last = case.loop.stages if case.loop is not None else 0
    aero = case_aero_groups(case)
    names = [s.name for n in range(last + 1) for s in stage_plan(case, n, aero=aero)]
    return names + [s.name for s in final_stages(case, last, [], aero)]

