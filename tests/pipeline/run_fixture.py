"""A small synthetic run folder laid out as the stage graph writes it (issue 11's contract).

Two configurations (EFEW, FFFW), stage 0 (baseline) and stage 1 (one tuning stage), SI units, two
sweeps per configuration (Mach 0.2 and 0.6 at 1.225 kg/m^3). The flutter crossings are chosen so
that Table 5's entries are known by hand (:data:`EXPECTED_CHANGE`):

=========  ====  ============  ===================  ===================  ==========================
config     Mach  flutter mode  stage 0 V, f          stage 1 V, f          change V, f [%]
=========  ====  ============  ===================  ===================  ==========================
EFEW       0.2   1st           200 m/s, 5.0 Hz      210 m/s, 4.9 Hz      +5, -2
EFEW       0.2   2nd           250 m/s, 8.0 Hz      240 m/s, 8.4 Hz      -4, +5
EFEW       0.6   1st           180 m/s, 5.5 Hz      189 m/s, 5.5 Hz      +5, 0
EFEW       0.6   2nd           (none)               230 m/s, 7.0 Hz      none (NaN)
FFFW       0.2   1st           190 m/s, 4.0 Hz      171 m/s, 4.4 Hz      -10, +10
FFFW       0.6   --            (none)               (none)               (no row)
=========  ====  ============  ===================  ===================  ==========================

The V-g / V-f sweeps cross g = 0 exactly there (g linear in V); participation.nc, correlation.nc,
history.nc and targets.json are hand-made Datasets with the contract's names; selection.nc comes
from pipeline.selection.select_modes and flutter_change.nc from pipeline.flutter_change, as the
stage graph writes them.
"""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import xarray as xr

from flutter.crossings import Crossing
from flutter.results import attach_crossings, vg_dataset, write_flutter
from flutter.summary import Envelope
from pipeline.case import Case, Configuration, FlutterSettings, LoopSettings, TuningSettings
from pipeline.flutter_change import flutter_change
from pipeline.selection import select_modes, selection_table
from structures.acceptance import evaluate_checks
from structures.common.files import write_dataset, write_json, write_text
from structures.correlation_plots import save_correlation_figures
from structures.massprops import MassProperties

CONFIGS = ("EFEW", "FFFW")
MACHS = (0.2, 0.6)
DENSITY = 1.225
VELOCITIES = np.linspace(100.0, 300.0, 21)
MODES = (1, 2, 3, 4)                       # mode 1 rigid (0 Hz), 2..4 flexible
FE_FREQUENCY = {0: (0.0, 3.0, 6.0, 9.0), 1: (0.0, 3.05, 5.9, 9.1)}
#: stage -> configuration -> case -> [(V [m/s], f [Hz]) of the 1st, 2nd ... flutter crossing]
CROSSINGS = {
    0: {"EFEW": {0: [(200.0, 5.0), (250.0, 8.0)], 1: [(180.0, 5.5)]},
        "FFFW": {0: [(190.0, 4.0)], 1: []}},
    1: {"EFEW": {0: [(210.0, 4.9), (240.0, 8.4)], 1: [(189.0, 5.5), (230.0, 7.0)]},
        "FFFW": {0: [(171.0, 4.4)], 1: []}},
}
#: (configuration, Mach, flutter mode) -> stage-1 (velocity change, frequency change) [%], by hand
EXPECTED_CHANGE = {("EFEW", 0.2, 1): (5.0, -2.0), ("EFEW", 0.2, 2): (-4.0, 5.0),
                   ("EFEW", 0.6, 1): (5.0, 0.0), ("EFEW", 0.6, 2): (None, None),
                   ("FFFW", 0.2, 1): (-10.0, 10.0)}
#: participation [%] of modes 1..4 in the 1st / 2nd flutter crossing of every sweep
PARTICIPATION = {1: (20.0, 55.0, 20.0, 5.0), 2: (10.0, 15.0, 70.0, 5.0)}
#: design variables: start, stage-1 tuned value, bounds (the second ends on its lower bound)
DESIGN = {"PBAR 11 I1": (1.0, 1.1, 0.8, 1.2), "CONM2 5 mass": (2.0, 1.6, 1.6, 2.4)}
STOP_REASON = ("the last stage allowed ([loop] stages = 1) ends with 1 primary-mode target(s) "
               "missed")


def _sweep(points: list, mach: float) -> xr.Dataset:
    """A 3-root p-k sweep whose root r crosses g = 0 at points[r - 1] (g = 0.002 (V - V_f))."""
    nv, nroot = VELOCITIES.size, 3
    damping = np.empty((nv, nroot))
    freq = np.empty((nv, nroot))
    crossings = []
    for r in range(nroot):
        if r < len(points):
            vf, ff = points[r]
            damping[:, r] = 0.002 * (VELOCITIES - vf)
            freq[:, r] = ff + 0.004 * (vf - VELOCITIES)
            i = int(np.searchsorted(VELOCITIES, vf) - 1)
            crossings.append(Crossing(r + 1, i, (vf - VELOCITIES[i]) / 10.0, vf, DENSITY, mach,
                                      ff, "flutter", True, False))
        else:
            damping[:, r] = -0.05 - 0.0004 * (VELOCITIES - 100.0) * (r + 1)
            freq[:, r] = 3.0 * (r + 1) - 0.002 * (VELOCITIES - 100.0)
    p = 2 * np.pi * freq * (damping / 2 + 1j)
    u = np.zeros((nv, nroot, len(MODES)), dtype=complex)
    for r in range(nroot):
        u[:, r, r + 1] = 1.0
    ds = vg_dataset(p, u, damping, np.ones((nv, nroot), bool), VELOCITIES,
                    np.full(nv, DENSITY), np.full(nv, mach), b=0.5, modes=MODES)
    return attach_crossings(ds, crossings)


def _participation(stage: int, config: str) -> xr.Dataset:
    """participation.nc of one configuration (contract names; shares of :data:`PARTICIPATION`)."""
    rows = [(c, MACHS[c], v, f, n + 1) for c, pts in CROSSINGS[stage][config].items()
            for n, (v, f) in enumerate(pts)]
    point = "flutter_point"
    col = list(zip(*rows))
    return xr.Dataset(
        {"participation": ((point, "mode"), np.array([PARTICIPATION[r[4]] for r in rows]),
                           {"units": "%"})},
        coords={"case": (point, np.array(col[0], int)), "mach": (point, np.array(col[1])),
                "density": (point, np.full(len(rows), DENSITY), {"units": "kg/m^3"}),
                "velocity": (point, np.array(col[2]), {"units": "m/s"}),
                "frequency": (point, np.array(col[3]), {"units": "Hz"}),
                "root": (point, np.array(col[4], int)),
                "flutter_mode": (point, np.array(col[4], int)),
                "mode": ("mode", np.array(MODES)),
                "rigid": ("mode", np.array(FE_FREQUENCY[stage]) < 0.05),
                "fe_frequency": ("mode", np.array(FE_FREQUENCY[stage]), {"units": "Hz"})},
        attrs={"configuration": config, "units": "si", "rigid_hz": 0.05})


def _modes(stage: int, config: str) -> xr.Dataset:
    """modes.nc: four mass-normalised modes on two grids (DESIGN.md section 6)."""
    shape = np.zeros((len(MODES), 12))
    for j in range(len(MODES)):
        shape[j, 2 + 6 * (j % 2)] = 1.0 + 0.1 * j
    return xr.Dataset(
        {"frequency": ("mode", np.array(FE_FREQUENCY[stage]), {"units": "Hz"}),
         "shape": (("mode", "dof"), shape), "generalized_mass": ("mode", np.ones(len(MODES)))},
        coords={"mode": np.array(MODES), "grid": ("dof", np.repeat([1, 2], 6)),
                "component": ("dof", np.tile(np.arange(1, 7), 2))},
        attrs={"source": "fixture", "deck": f"{config}.bdf", "units": "si"})


def _correlation(stage: int, config: str) -> xr.Dataset:
    """correlation.nc: test modes 1..3 paired with FE modes 2..4, checks merged as correlate does."""
    f_test = np.array([3.0, 6.2, 9.0])
    f_fe = np.array(FE_FREQUENCY[stage])
    paired = np.array([2, 3, 4])
    cross = np.array([[0.02, 0.99, 0.05, 0.01], [0.01, 0.04, 0.97, 0.12 - 0.04 * stage],
                      [0.00, 0.02, 0.03, 0.98]])
    ortho = np.array([[1.0, 0.03, 0.01], [0.03, 1.0, 0.05], [0.01, 0.05, 1.0]])
    mac = cross ** 2
    t, tf = ("test_mode",), ("test_mode", "fe_mode")
    ds = xr.Dataset(
        {"mac": (tf, mac), "orthogonality": (("test_mode", "test_mode_2"), ortho),
         "cross_orthogonality": (tf, cross),
         "frequency_error": (t, 100.0 * (f_fe[paired - 1] - f_test) / f_test, {"units": "%"}),
         "paired_fe_mode": (t, paired), "paired_fe_frequency": (t, f_fe[paired - 1], {"units": "Hz"}),
         "paired_mac": (t, mac[np.arange(3), paired - 1]), "interchanged": (t, np.zeros(3, bool)),
         "test_frequency": (t, f_test, {"units": "Hz"}), "test_damping": (t, np.full(3, 0.01)),
         "test_generalized_mass": (t, np.ones(3)), "fe_frequency": (("fe_mode",), f_fe),
         "test_name": (t, np.array(["SW1B", "SW1T", "SW2B"], dtype=object))},
        coords={"test_mode": [1, 2, 3], "test_mode_2": [1, 2, 3], "fe_mode": list(MODES)},
        attrs={"interchanges": "none"})
    if config == "EFEW":
        ds = ds.merge(xr.Dataset(
            {"mass_model": ("quantity", [100.0, 1.0]), "mass_measured": ("quantity", [98.0, 1.0]),
             "mass_error": ("quantity", [2.0, 0.0]),
             "mass_relative_error": ("quantity", [100 * 2.0 / 98.0, 0.0], {"units": "%"})},
            coords={"quantity": ["weight", "x_cg"]}))
    checks = evaluate_checks(ds)
    return xr.merge([ds, checks], combine_attrs="override").assign_attrs(checks.attrs)


def _history() -> xr.Dataset:
    """stage1/tuning/history.nc: three evaluations, the last the tuned design."""
    start = np.array([v[0] for v in DESIGN.values()])
    end = np.array([v[1] for v in DESIGN.values()])
    design = np.array([start, 0.5 * (start + end), end])
    pairs = [f"{c}:{t}" for c in CONFIGS for t in (1, 2, 3)]
    f_fe = np.array([[3.0, 6.0, 9.0] * 2, [3.02, 5.95, 9.05] * 2, [3.05, 5.9, 9.1] * 2])
    pr = ("iteration", "pair")
    return xr.Dataset(
        {"design": (("iteration", "design_variable"), design),
         "objective": ("iteration", [1.0, 0.5, 0.2]), "feasible": ("iteration", [True] * 3),
         "max_violation": ("iteration", np.zeros(3)),
         "paired_fe_mode": (pr, np.tile([2, 3, 4], (3, 2))),
         "paired_fe_frequency": (pr, f_fe, {"units": "Hz"}),
         "interchanged": (pr, np.zeros((3, 6), bool))},
        coords={"iteration": np.arange(3), "design_variable": list(DESIGN), "pair": pairs,
                "test_frequency": ("pair", [3.0, 6.2, 9.0] * 2, {"units": "Hz"}),
                "lower": ("design_variable", [v[2] for v in DESIGN.values()]),
                "upper": ("design_variable", [v[3] for v in DESIGN.values()]),
                "start": ("design_variable", start)},
        attrs={"stage": 1})


def _targets(stage: int) -> dict:
    failing = [{"configuration": "EFEW", "test_mode": 2, "fe_mode": 3,
                "check": "frequency error [%]", "value": -4.84, "limit": 3.0}]
    if stage == 0:
        failing.append({"configuration": "FFFW", "test_mode": None, "fe_mode": 4,
                        "check": "paired test mode", "value": None, "limit": None})
    return {"standard": "MIL-STD-1540C", "stage": stage, "met": False,
            "stop_reason": STOP_REASON if stage == 1 else "", "failing": failing}


def make_case(inputs: Path) -> Case:
    """The case of the fixture (placeholder decks and GVT files in ``inputs``)."""
    inputs.mkdir(parents=True, exist_ok=True)
    configs = []
    for name in CONFIGS:
        (inputs / f"{name}.bdf").write_text("BEGIN BULK\nENDDATA\n")
        (inputs / f"{name}.unv").write_text("    -1\n")
        configs.append(Configuration(name=name, deck=inputs / f"{name}.bdf",
                                     gvt=inputs / f"{name}.unv"))
    return Case(name="fixture", configurations=tuple(configs), units="si",
                flutter=FlutterSettings(structural_damping=0.01,
                                        envelope=Envelope((0.2, 0.6), (160.0, 170.0), "m/s")),
                tuning=TuningSettings(variables=(), objective=()), loop=LoopSettings(stages=1))


def make_run(root: Path) -> tuple[Case, Path]:
    """Write the run folder under ``root / "run"``; returns the case and the run folder."""
    case = make_case(root / "inputs")
    run = root / "run"
    parts = []
    for stage in (0, 1):
        folder = run / f"stage{stage}"
        parts.append({})
        for config in CONFIGS:
            base = folder / config
            write_dataset(_modes(stage, config), base / "modes.nc")
            props = MassProperties(100.0 - stage, np.array([1.0, 0.0, 0.1]),
                                   np.array([[10.0, -0.5, 0.0], [-0.5, 20.0, 0.0], [0.0, 0.0, 30.0]]),
                                   np.eye(6), np.zeros(3))
            write_dataset(props.to_dataset(), base / "mass_properties.nc")
            corr = _correlation(stage, config)
            write_dataset(corr, base / "correlation.nc")
            save_correlation_figures(corr, base / "correlation")
            sweeps = [_sweep(CROSSINGS[stage][config][c], MACHS[c]) for c in range(len(MACHS))]
            labels = [{"mach": m, "density": DENSITY, "configuration": config} for m in MACHS]
            write_flutter(base / "flutter", sweeps, labels, units="si", title=config)
            parts[stage][config] = _participation(stage, config)
            write_dataset(parts[stage][config], base / "flutter" / "participation.nc")
        pairing = {c: {2: 1, 3: 2, 4: 3} for c in CONFIGS}
        selection = select_modes(parts[stage], pairing=pairing)
        write_dataset(selection, folder / "selection.nc")
        write_text(selection_table(selection) + "\n", folder / "selection.txt")
        write_json(_targets(stage), folder / "targets.json")
    write_dataset(_history(), run / "stage1" / "tuning" / "history.nc")
    write_text("fixture tuning report\n", run / "stage1" / "tuning" / "report.txt")
    for config in CONFIGS:
        write_text("BEGIN BULK\nENDDATA\n", run / "stage1" / "tuning" / f"{config}_tuned.bdf")
    write_dataset(flutter_change(parts), run / "flutter_change.nc")
    outputs = {str(p.relative_to(run)): hashlib.sha256(p.read_bytes()).hexdigest()
               for p in sorted(run.rglob("*")) if p.is_file()}
    (run / "manifest.json").write_text(json.dumps(
        {"fixture": {"fingerprint": "fixture", "outputs": outputs}}, indent=2))
    return case, run
