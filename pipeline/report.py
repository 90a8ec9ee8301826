"""The run's HTML report: one self-contained page built from the run folder (no computation).

:func:`write_report` reads the files of the run folder (layout in the stage graph's contract:
``stage<n>/<config>/modes.nc, mass_properties.nc, correlation.nc, correlation/*.png,
flutter/flutter.nc, flutter/summary.json``, ``stage<n>/selection.nc``, ``stage<n>/targets.json``,
``stage<n>/tuning/history.nc`` and ``flutter_change.nc``) and writes ``report.html`` beside them.
Sections: the case and the stages run with the loop's stop reason; the flutter speed and frequency
change per stage (paper Table 5, ``<table id="flutter-change">``); the flutter boundary against the
envelope with the 15 % margin; V-g / V-f of every stage overlaid (Figs. 11, 12, 17); the
design-variable changes (Table 24); then per stage and configuration the test-analysis frequency
table with MAC, the orthogonality / cross-orthogonality off-diagonals and the acceptance checks,
the correlation maps, the mass properties and the flutter crossings, and per stage the participation
and selection table (Table 6). A diagnosis in the run folder adds its section
(pipeline.report_diagnose) before the stages. Every figure is embedded as a PNG data URI, so the page renders offline
with nothing beside it; every number carries its unit (structures.units); a missing optional piece
(no GVT, no tuning stage, no envelope, no flutter) is left out with one line saying why.

The stages shown are those of this run: stage 0, then the tuning stages up to the one whose
targets.json states why the loop stopped (at most the case's ``[loop] stages``).
"""
from __future__ import annotations

import html
import json
from pathlib import Path

import numpy as np

from flutter.summary import BFF_SHARE, classify
from pipeline.report_diagnose import diagnose_section
from pipeline.report_figures import (boundary_figure, figure_data_uri, png_data_uri, vg_overlay)
from pipeline.report_tables import (correlation_section, design_change_section, fmt,
                                    mass_section, modes_section, note, selection_roles,
                                    selection_section, table, tuning_section)
from pipeline.selection import ordinal
from structures.common.errors import InputError
from structures.common.files import read_dataset, write_text
from structures.units import UnitLabels, unit_labels

_STYLE = """body{font-family:sans-serif;margin:2em;max-width:80em;color:#222}
table{border-collapse:collapse;margin:0.5em 0 1.5em}td,th{border:1px solid #bbb;padding:2px 8px;
text-align:right}th{background:#e8eef6}td:first-child{text-align:left}h2{border-bottom:2px solid #456;
color:#234}h3{color:#345}img{border:1px solid #ccc;margin:4px}p.note{color:#555;font-style:italic}
pre{background:#f6f6f6;padding:6px;overflow-x:auto}"""


def _stage_label(k: int) -> str:
    return "stage 0 (baseline)" if k == 0 else f"stage {k} (tuning {k})"


def _read_json(path: Path):
    return json.loads(path.read_text()) if path.exists() else None


def _text(value) -> str:
    return "\u2013" if value is None else str(value)


def _nan(value) -> float:
    return np.nan if value is None else float(value)


def _check_unit(check: str) -> str:
    """Unit of a targets.json check's value and limit."""
    if "frequency" in check:
        return "%"
    return "- (|S_ij|)" if "orthogonality" in check else "-"


def stage_folders(run_dir: Path, case) -> list[Path]:
    """``stage0``, ``stage1``, ... of this run in order: contiguous from stage 0, at most the case's
    [loop] stages, and none after a stage whose targets.json gives the loop's stop reason (folders
    of an earlier, longer run are left out)."""
    run_dir = Path(run_dir)
    if not (run_dir / "stage0").is_dir():
        raise InputError(f"run folder {run_dir}: no stage0/ folder. Fix: run `pipeline run CASE` "
                         "into this folder first (the report reads its results).")
    last = case.loop.stages if case.loop is not None else 0
    out = []
    for k in range(last + 1):
        folder = run_dir / f"stage{k}"
        if not folder.is_dir():
            break
        out.append(folder)
        targets = _read_json(folder / "targets.json")
        if targets is not None and targets.get("stop_reason"):
            break
    return out


def _overview(case, stages: list[Path], labels: UnitLabels) -> str:
    configs = table(("configuration", "deck", "GVT"),
                    [(c.name, str(c.deck), str(c.gvt) if c.gvt else "none (no correlation)")
                     for c in case.configurations])
    rows, failing = [], []
    for k, folder in enumerate(stages):
        targets = _read_json(folder / "targets.json")
        if targets is None:
            rows.append((_stage_label(k), "", "", "no targets.json (no [loop] or no GVT)"))
            continue
        rows.append((_stage_label(k), targets["standard"], "yes" if targets["met"] else "no",
                     targets["stop_reason"] or "the loop goes on"))
        if k == len(stages) - 1:
            failing = [(k, f["configuration"], _text(f["test_mode"]), _text(f["fe_mode"]),
                        f["check"], fmt(_nan(f["value"]), ".4g"), fmt(_nan(f["limit"]), ".4g"),
                        _check_unit(f["check"])) for f in targets.get("failing", [])]
    out = (f"<h1>Case {html.escape(case.name)}</h1><p>Unit system: {html.escape(labels.system)} ("
           + html.escape(", ".join(f"{q} [{getattr(labels, q)}]" for q in
                                   ("length", "velocity", "density", "mass", "inertia", "force",
                                    "frequency"))) + ").</p>" + configs +
           '<h2 id="stages">Stages run</h2>' +
           table(("stage", "standard", "primary-mode targets met [yes/no]", "stop reason"), rows))
    if len(stages) == 1:
        out += note("No tuning stage was run (no [loop] with stages >= 1, or the targets held "
                    "at stage 0): the report shows the baseline only.")
    if failing:
        out += "<h3>Primary-mode targets still failing after the last stage</h3>" + table(
            ("stage", "configuration", "test mode", "FE mode", "check", "value [unit column]",
             "limit [unit column]", "unit"), failing)
    return out


def mechanisms(folder: Path, config: str) -> list[tuple]:
    """Flutter mechanism of every flutter point of one stage and configuration.

    Parameters
    ----------
    folder : Path
        The stage folder (``stage<n>/``).
    config : str
        The configuration.

    Returns
    -------
    list of tuple
        ``(case, root, flutter_mode, velocity, mechanism)`` per flutter point of
        ``<config>/flutter/participation.nc`` ([] without one): :func:`flutter.summary.classify`
        ("body-freedom: R-F" when the rigid-body modes take >= BFF_SHARE of the root's
        participation, R and F its largest rigid and flexible modes, else
        the two most participating flexible modes), each mode named by its paired GVT test mode
        (``<config>/correlation.nc`` ``test_name`` / ``paired_fe_mode``; "mode n" when unpaired).
    """
    path = folder / config / "flutter" / "participation.nc"
    if not path.exists():
        return []
    part = read_dataset(path)
    corr_path = folder / config / "correlation.nc"
    corr = read_dataset(corr_path) if corr_path.exists() else None
    names = ({} if corr is None or "test_name" not in corr else
             {int(fe): str(name) for fe, name in zip(corr["paired_fe_mode"].values,
                                                     corr["test_name"].values) if str(name)})
    return [(int(part["case"].values[i]), int(part["root"].values[i]),
             int(part["flutter_mode"].values[i]), float(part["velocity"].values[i]),
             classify(part, i, names)) for i in range(part.sizes["flutter_point"])]


def _mechanism_of(points: list[tuple], entry: dict) -> str:
    """Mechanism of one summary.json crossing (same case, root and speed); "\u2013" if none."""
    for case, root, _, velocity, name in points:
        if (case == entry.get("case", 0) and root == entry["root"]
                and np.isclose(velocity, entry["velocity"], rtol=1e-9)):
            return name
    return "\u2013"


def _flutter_change_section(run_dir: Path, case, stages: list[Path], labels: UnitLabels) -> str:
    head = '<h2 id="table5">Flutter speed and frequency per stage (paper Table 5)</h2>'
    path = run_dir / "flutter_change.nc"
    if not path.exists():
        return head + note("No flutter_change.nc in the run folder (no [flutter] section or no "
                            "flutter stage): no flutter-change table.")
    fc = read_dataset(path)
    if fc.sizes["case"] == 0 or fc.sizes["flutter_mode"] == 0:
        return head + note("No flutter crossing at any stage, Mach or configuration.")
    v_u = fc["velocity"].attrs.get("units", labels.velocity)
    d_u = fc["density"].attrs.get("units", labels.density)
    numbers = fc["stage"].values
    named = {(k, c.name): {(p[0], p[2]): p[4] for p in mechanisms(folder, c.name)}
             for k, folder in enumerate(stages) for c in case.configurations}
    matched = "keas" in fc and bool(np.isfinite(fc["keas"].values).any())
    header = ["configuration", "Mach [-]", f"density [{d_u}]", "flutter mode",
              f"stage 0 speed [{v_u}]"] + (["stage 0 KEAS [kn]"] if matched else []) + [
              "stage 0 frequency [Hz]", "stage 0 mechanism"]
    for k in numbers[1:]:
        header += ([f"stage {k} speed [{v_u}]", f"stage {k} speed change [%]"] +
                   ([f"stage {k} KEAS [kn]", f"stage {k} KEAS change [%]"] if matched else []) +
                   [f"stage {k} frequency [Hz]", f"stage {k} frequency change [%]",
                    f"stage {k} mechanism"])
    rows = []
    for config in fc["configuration"].values:
        for case in fc["case"].values:
            for mode in fc["flutter_mode"].values:
                one = fc.sel(configuration=config, case=case, flutter_mode=mode)
                if np.all(np.isnan(one["velocity"].values)):
                    continue
                row = ([str(config), fmt(one["mach"], ".4g"), fmt(one["density"], ".5g"),
                        ordinal(int(mode)), fmt(one["velocity"].sel(stage=0), ".5g")] +
                       ([fmt(one["keas"].sel(stage=0), ".4g")] if matched else []) +
                       [fmt(one["frequency"].sel(stage=0), ".4g"),
                        named.get((0, str(config)), {}).get((int(case), int(mode)), "\u2013")])
                for k in numbers[1:]:
                    at = one.sel(stage=k)
                    row += ([fmt(at["velocity"], ".5g"), fmt(at["velocity_change"], "+.2f")] +
                            ([fmt(at["keas"], ".4g"), fmt(at["keas_change"], "+.2f")]
                             if matched else []) +
                            [fmt(at["frequency"], ".4g"), fmt(at["frequency_change"], "+.2f"),
                             named.get((int(k), str(config)), {}).get((int(case), int(mode)),
                                                                       "\u2013")])
                rows.append(row)
    return (head + "<p>The n-th flutter crossing (by speed) of each sweep at stage k against the "
            "n-th at stage 0; change = 100 (stage k - stage 0) / stage 0, signed (positive: "
            "faster / higher). \u2013: no such crossing at that stage (no change is given). "
            f"Mechanism: body-freedom (its largest rigid-body and flexible modes) when the "
            f"rigid-body modes take >= {BFF_SHARE:g} % of the root's participation, else its two "
            "most participating flexible modes, named by their "
            "paired GVT test modes (\"mode n\": unpaired). KEAS (matched-point flutter): the "
            "equivalent airspeed, which changes where the true airspeed M a(h) of a matched "
            "line does not (constant speed of sound, 11-20 km).</p>"
            + table(header, rows, table_id="flutter-change"))


def _crossings(stages: list[Path], case) -> list[dict]:
    """summary.json entries per stage and configuration."""
    out = []
    for folder in stages:
        out.append({c.name: data for c in case.configurations
                    if (data := _read_json(folder / c.name / "flutter" / "summary.json"))
                    is not None})
    return out


def _boundary_section(case, stages: list[Path], labels: UnitLabels) -> str:
    head = '<h2 id="boundary">Flutter boundary against the flight envelope</h2>'
    crossings = _crossings(stages, case)
    if not any(entries for stage in crossings for entries in stage.values()):
        return head + note("No flutter or divergence crossing in any stage: no boundary to draw.")
    envelope = case.flutter.envelope if case.flutter is not None else None
    fig = boundary_figure(crossings, [_stage_label(k) for k in range(len(stages))], envelope,
                          units=labels.velocity)
    out = head + (note("No envelope in the case's [flutter]: the boundary is drawn without the "
                        "envelope and its 1.15 x margin.") if envelope is None else
                  "<p>Envelope and 1.15 x envelope (the 15 % flutter margin) from the case's "
                  "[flutter] envelope.</p>")
    return out + f'<img src="{figure_data_uri(fig)}" alt="flutter boundary" width="640">'


def _overlay_section(case, stages: list[Path], labels: UnitLabels) -> str:
    out = '<h2 id="vg">V-g / V-f of every stage overlaid (paper Figs. 11, 12, 17)</h2>'
    names = [_stage_label(k) for k in range(len(stages))]
    for config in case.configurations:
        files = [folder / config.name / "flutter" / "flutter.nc" for folder in stages]
        if not files[0].exists():
            out += note(f"Configuration {config.name}: no flutter.nc at stage 0 (no flutter run).")
            continue
        present = [(read_dataset(f), name) for f, name in zip(files, names) if f.exists()]
        base = present[0][0]
        for c in base["case"].values:
            where = [f"{name} {base[key].values[c]:.4g} [{unit}]"
                     for key, name, unit in (("case_mach", "Mach", "-"),
                                             ("case_density", "density", labels.density))
                     if key in base.coords and np.isfinite(base[key].values[c])]
            title = f"{config.name}: " + ", ".join(where or [f"sweep {int(c) + 1}"])
            fig = vg_overlay([ds for ds, _ in present], int(c), [n for _, n in present],
                             title=title)
            out += (f'<h3>Configuration {html.escape(title)}</h3><img src="{figure_data_uri(fig)}" '
                    f'alt="V-g / V-f {html.escape(title)}" width="620">')
    return out


#: How each summary.json "method" is named in the report's crossing tables.
METHOD_NAMES = {"PK": "p-k (PK)", "PKNL": "p-k (PKNL)", "K": "k-method",
                "KE": "k-method", "G": "g-method", "P-RFA": "p-method on a rational fit"}


def _crossing_table(entries: list[dict], points: list[tuple], labels: UnitLabels) -> str:
    if not entries:
        return note("No flutter or divergence crossing in the analysed range.")
    rows = [(e["kind"], f"{e['root']} ({e['root_label']})" if e.get("root_label") else e["root"],
             fmt(e["mach"], ".4g"), fmt(e["density"], ".5g"),
             fmt(e["velocity"], ".5g"), fmt(e["frequency"], ".4g"), _mechanism_of(points, e),
             METHOD_NAMES.get(str(e.get("method", "")), str(e.get("method", ""))))
            for e in sorted(entries, key=lambda e: (e.get("case", 0), e["velocity"]))]
    return table(("kind", "root", "Mach [-]", f"density [{labels.density}]",
                  f"velocity [{labels.velocity}]", "frequency [Hz]", "mechanism", "method"), rows)


def _stage_section(k: int, folder: Path, case, labels: UnitLabels) -> str:
    out = f'<h2 id="stage{k}">{html.escape(_stage_label(k).capitalize())}</h2>'
    if k:
        out += tuning_section(k, folder / "tuning" / "history.nc")
    roles = selection_roles(folder / "selection.nc")
    for config in case.configurations:
        where = f"Stage {k}, configuration {config.name}"
        out += f"<h3>{html.escape(where)}</h3>"
        base = folder / config.name
        corr_path = base / "correlation.nc"
        if corr_path.exists():
            corr = read_dataset(corr_path)
            out += correlation_section(corr, where, roles.get(config.name))
            maps = sorted((base / "correlation").glob("*.png"))
            out += "".join(f'<img src="{png_data_uri(p.read_bytes())}" alt="{html.escape(where)} '
                           f'{html.escape(p.stem)}" width="380">' for p in maps)
        else:
            corr = None
            out += note(f"{where}: no GVT for this configuration, so no correlation.")
            if (base / "modes.nc").exists():
                out += modes_section(read_dataset(base / "modes.nc"), where)
        if (base / "mass_properties.nc").exists():
            out += mass_section(read_dataset(base / "mass_properties.nc"), corr, labels, where)
        summary = _read_json(base / "flutter" / "summary.json")
        if summary is not None:
            out += (f"<h4>{html.escape(where)}: flutter crossings</h4>" +
                    _crossing_table(summary, mechanisms(folder, config.name), labels))
    out += selection_section(k, folder / "selection.nc")
    return out


def write_report(case, run_dir, *, out=None) -> Path:
    """Write the report of a run folder and return its path.

    Parameters
    ----------
    case : pipeline.case.Case
        The case (name, unit system, configurations, flutter envelope).
    run_dir : path
        The run folder (layout in the module docstring).
    out : path, optional
        Where to write the page (default ``run_dir / "report.html"``; the stage graph passes its
        staging path).

    Returns
    -------
    Path
        The page, written atomically (structures.common.files.write_text).

    Raises
    ------
    InputError
        The run folder has no ``stage0/``.
    """
    run_dir = Path(run_dir)
    labels = unit_labels(case.units)
    stages = stage_folders(run_dir, case)
    body = (_overview(case, stages, labels) +
            _flutter_change_section(run_dir, case, stages, labels) +
            (_boundary_section(case, stages, labels) + _overlay_section(case, stages, labels)
             if case.flutter is not None else
             note("No [flutter] section in the case: no flutter boundary and no V-g / V-f.")) +
            design_change_section(stages[1:]) + diagnose_section(run_dir, labels) +
            "".join(_stage_section(k, folder, case, labels) for k, folder in enumerate(stages)))
    page = (f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>'
            f"{html.escape(case.name)}: pipeline run report</title><style>{_STYLE}</style></head>"
            f"<body>{body}</body></html>")
    return write_text(page, Path(out) if out is not None else run_dir / "report.html")
