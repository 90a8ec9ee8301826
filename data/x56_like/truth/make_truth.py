"""The "aircraft that was tested": a truth model of the X-56A-class example and its synthetic GVT.

The pipeline never imports this script; it only reads what the script writes beside the analysis
model (``data/x56_like/``):

* ``gvt_efew.unv``, ``gvt_fffw.unv``: UFF 15 + 55, the truth model's six suspension modes
  (modes 1-6, named ``suspension 1`` ..) and its first ``N_TEST`` elastic modes (7, 8, ...: the
  reference paper's numbers) of each configuration at ``sensors()`` (120 translations in the
  basic frame; node ids are the analysis model's grid ids, node positions the analysis model's
  grid positions),
  names as the pre-test analysis gives them (``test_names``), 1 % frequency noise,
  5 % shape noise (white, independent per DOF, standard deviation 5 % of the mode's RMS over the
  sensors), viscous damping zeta drawn uniformly in 1-2 %;
* ``mass_efew.json``, ``mass_fffw.json``: the truth model's weight (lb), CG (in) and inertia
  tensor about the CG, ``inertia_cg = [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]`` in the deck's mass units
  (lbf s^2 in, i.e. after PARAM WTMASS) with the products Ixy = sum m x y
  (structures.massprops.read_measured_mass);
* ``sensors.csv``: the sensor layout (grid, component, direction, component of the aircraft).

The truth differs from the analysis model (``make_model.ANALYSIS``) in the ways the reference paper
found or suspected (Pak & Truong, X-56A GVT-validated FE model, Fig. 16 and sec. IV), built with the
generator's hooks (``dataclasses.replace`` of ``X56Parameters``) -- see ``truth_parameters`` and
``README.md`` beside this script for the values:

* main landing gear: tapered (``MAIN_GEAR_ROOT`` x the model's section size at the root,
  ``MAIN_GEAR_TAPER`` tip/root) and curved (``MAIN_GEAR_BOW`` in lateral bow),
  ``MAIN_GEAR_SEGMENTS`` segments, where the model has two uniform straight bars;
* engines on six CELAS2 mount springs (``ENGINE_MOUNT``) where the model has an RBE2;
* ``CABLE_WEIGHT`` lb of GVT sensor cables spread along both wings' elastic axes;
* the soft suspension: three bungees from ground points 60 in above the nose-gear bay and the
  wings' mid-span, vertical stiffness ``BUNGEE_VERTICAL`` each and pendulum stiffness (x and y)
  ``make_model.SUSPENSION_PENDULUM`` times it, so the six rigid-body modes sit at 0.3-1.5 Hz;
* scatter within manufacturing tolerance, drawn from ``SEED``: Young's modulus (sigma
  ``E_SCATTER``), every PBAR's A, I1, I2, J on both sides independently (sigma
  ``PROPERTY_SCATTER``) and every CONM2's mass and inertia (sigma ``MASS_SCATTER``), all clipped at
  two sigma.

The truth decks are written into a temporary folder and not kept (``--decks DIR`` keeps them).
Byte-deterministic from the seed at one BLAS thread count: the scatter and the noise come from
``numpy.random.default_rng((SEED, stream))`` and every mode shape's sign is fixed (largest sensor
entry positive) before noise is added. (The FFFW truth's two sway suspension modes lie 2.5e-5
apart; the eigensolver mixes them by ~2.5e-6 differently at another thread count, which can move
a printed sixth digit of their shapes.) Run from the repository root::

    python data/x56_like/truth/make_truth.py [--out FOLDER] [--decks DIR]
"""
from __future__ import annotations

import argparse
import csv
import io
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import xarray as xr

HERE = Path(__file__).resolve().parent
MODEL_DIR = HERE.parent
sys.path.insert(0, str(MODEL_DIR))
sys.path.insert(0, str(MODEL_DIR.parents[1]))

import make_model as mm  # noqa: E402
from mode_names import classify_modes  # noqa: E402
from structures.assembly import assemble  # noqa: E402
from structures.bdf import read_model  # noqa: E402
from structures.common.errors import InputError  # noqa: E402
from structures.common.files import write_json, write_text  # noqa: E402
from structures.correlation import mac  # noqa: E402
from structures.gvt import make_gvt_dataset, write_uff  # noqa: E402
from structures.massprops import mass_properties  # noqa: E402
from structures.modal import compute_modes  # noqa: E402

#: Seed of every random draw (scatter: stream 0; noise of configuration i: stream i + 1, of its
#: suspension modes stream i + 1 + ``SUSPENSION_STREAM``).
SEED = 20121217                      # the X-56A GVT date
#: Elastic modes "measured" per configuration (all below 40 Hz).
N_TEST = 22
#: Rigid-body (suspension) modes of the truth model, below the first elastic mode; the GVT files
#: list them first (modes 1-6), as a GVT report does.
N_RIGID = 6
SUSPENSION_STREAM = 100
FREQUENCY_NOISE = 0.01               # standard deviation, fraction of the frequency
SHAPE_NOISE = 0.05                   # standard deviation, fraction of the mode's RMS at the sensors
DAMPING = (0.010, 0.020)             # zeta, uniform
E_SCATTER = 0.01
PROPERTY_SCATTER = 0.03
MASS_SCATTER = 0.02
MAIN_GEAR_ROOT = 1.05                # root section size / the model's (area ~ r^2, I ~ r^4)
MAIN_GEAR_TAPER = 0.75               # tip / root section size
MAIN_GEAR_BOW = 2.0                  # in, lateral offset of the leg's middle
MAIN_GEAR_SEGMENTS = 4
ENGINE_MOUNT = (1.0e4, 1.0e4, 1.6e4, 1.5e5, 1.5e5, 1.5e5)     # lbf/in (T1-T3), lbf in/rad (R1-R3)
#: A test mode takes the name of the pre-test analysis mode it matches at least this well (MAC).
NAME_MAC = 0.8
CABLE_WEIGHT = 8.0                   # lb, both wings
BUNGEE_VERTICAL = 8.0                # lbf/in per bungee (x, y: make_model.SUSPENSION_PENDULUM x it)
UNITS = "english_in"

# Sensor layout: (analysis grid ids, components) per part of the aircraft; right side, the left
# side of a wing / winglet grid is +1000 and of an engine / gear grid +100.
_STATIONS = range(len(mm.WING_Y))
_SIDED = (
    ("wing", [3101 + i for i in _STATIONS] + [3201 + i for i in _STATIONS], (3,)),
    ("wing", [3002, 3004, 3006, 3008, 3010], (3,)),
    ("wing", [3003, 3006, 3010], (1,)),
    ("wing", [3010], (2,)),
    ("winglet", [3401, 3402, 3403, 3501, 3502, 3503], (2,)),
    ("winglet", [3303], (1,)),
    ("engine", [5011, 5021], (1, 2, 3)),
    ("main gear", [6102, 6103], (1, 2, 3)),
)
_CENTRE = (
    ("centre body", [1001 + i for i in range(len(mm.SPINE_X))], (3,)),
    ("centre body", [1001, 1003, 1005, 1007], (2,)),
    ("centre body", [1001, 1007], (1,)),
    ("carry-through", [2001, 2101], (3,)),
    ("boom", [1101, 1102], (2, 3)),
    ("nose gear", [6001], (1, 2)),
    ("nose gear", [6002], (1, 2, 3)),
)


def sensors() -> list[tuple[int, int, str]]:
    """The 120 measured DOFs: (analysis grid id, component 1..3 in the basic frame, part), sorted."""
    out = []
    for part, grids, comps in _SIDED:
        left = 1000 if part in ("wing", "winglet") else 100
        out += [(g + s, c, part) for g in grids for s in (0, left) for c in comps]
    out += [(g, c, part) for part, grids, comps in _CENTRE for g in grids for c in comps]
    return sorted(out)


def sensors_csv() -> str:
    """The sensor layout as CSV text (grid, component, direction, part, x, y, z of the model grid)."""
    xyz = mm._grids(mm.ANALYSIS)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["grid", "component", "direction", "part", "x_in", "y_in", "z_in"])
    for g, c, part in sensors():
        w.writerow([g, c, "xyz"[c - 1], part, *(f"{v:g}" for v in xyz[g])])
    return buf.getvalue()


def _clipped(rng: np.random.Generator, sigma: float, n: int) -> np.ndarray:
    """n factors 1 + sigma * N(0, 1), the normal draw clipped at +-2."""
    return 1.0 + sigma * np.clip(rng.standard_normal(n), -2.0, 2.0)


def _pbar_ids(params: mm.X56Parameters) -> list[int]:
    return sorted(int(line[8:16]) for line in mm.structure_bulk(params) if line.startswith("PBAR"))


def truth_parameters(seed: int = SEED) -> mm.X56Parameters:
    """The truth model: the analysis model with the paper's suspected modelling errors, the
    suspension and the manufacturing scatter drawn from ``seed`` (module docstring)."""
    base = replace(mm.ANALYSIS, main_gear=mm.ANALYSIS.main_gear.scaled(MAIN_GEAR_ROOT),
                   main_gear_segments=MAIN_GEAR_SEGMENTS, main_gear_taper=MAIN_GEAR_TAPER,
                   main_gear_bow=MAIN_GEAR_BOW, engine_mount=ENGINE_MOUNT,
                   cable_weight=CABLE_WEIGHT, suspension=BUNGEE_VERTICAL)
    rng = np.random.default_rng((seed, 0))
    pids = _pbar_ids(base)
    fields = ("A", "I1", "I2", "J")
    pf = _clipped(rng, PROPERTY_SCATTER, len(pids) * len(fields))
    conm2 = sorted({m.eid for c in mm.CONFIGURATIONS for m in mm.mass_items(base, c)})
    mf = _clipped(rng, MASS_SCATTER, len(conm2))
    e = float(_clipped(rng, E_SCATTER, 1)[0])
    return replace(base, E=base.E * e,
                   property_factors=tuple((p, f, float(x)) for (p, f), x in
                                          zip(((p, f) for p in pids for f in fields), pf)),
                   mass_factors=tuple((eid, float(x)) for eid, x in zip(conm2, mf)))


def truth_grid(grid: int, params: mm.X56Parameters) -> int:
    """The truth model's grid at an analysis model's grid (the main gear has more segments)."""
    if mm.component_of(grid) != "main gear":
        return grid
    base = 6201 if grid >= 6200 else 6101
    step, rest = divmod(params.main_gear_segments, mm.ANALYSIS.main_gear_segments)
    if rest:
        raise InputError(f"truth main_gear_segments = {params.main_gear_segments}: must be a "
                         f"multiple of the analysis model's {mm.ANALYSIS.main_gear_segments}. "
                         "Fix: change MAIN_GEAR_SEGMENTS.")
    return base + (grid - base) * step


def deck_modes(folder: Path, configuration: str, nmodes: int = N_RIGID + N_TEST + 12) -> tuple:
    """Modes (our solver, deck mass) and mass properties of a configuration's deck in ``folder``."""
    model = read_model(folder / f"x56_{configuration}.bdf")
    system = assemble(model, "deck")
    return (compute_modes(model, nmodes, mass="deck", system=system),
            mass_properties(model, m_basic=system.m_basic))


def sensor_shapes(modes: xr.Dataset, params: mm.X56Parameters) -> np.ndarray:
    """Shapes at the ``sensors()`` of a model built from ``params``, shape (n_mode, 120)."""
    key = {(int(g), int(c)): j for j, (g, c) in
           enumerate(zip(modes["grid"].values, modes["component"].values))}
    return modes["shape"].values[:, [key[(truth_grid(g, params), c)] for g, c, _ in sensors()]]


def test_names(truth: np.ndarray, own: list[str], analysis: np.ndarray,
               analysis_names: list[str]) -> list[str]:
    """Names of the test modes as a pre-test analysis gives them.

    A test mode takes the name of the analysis mode it matches best when their MAC at the sensors
    is at least ``NAME_MAC`` and no better-matching test mode took it (greedy, best MAC first);
    otherwise its own name from its shape (``own``). Repeated names get a suffix ``-2``, ``-3``.

    Parameters
    ----------
    truth : (n_test, n_sensor) noise-free test shapes
    own : n_test names from the test shapes (mode_names.classify_modes)
    analysis : (n_fe, n_sensor) analysis shapes
    analysis_names : n_fe names (mode_names.classify_modes)
    """
    m = mac(truth.T, analysis.T)
    names = list(own)
    named: set = set()
    taken: set = set()
    for flat in np.argsort(-m, axis=None, kind="stable"):
        i, j = divmod(int(flat), m.shape[1])
        if m[i, j] < NAME_MAC:
            break
        if i not in named and j not in taken and analysis_names[j] != "RB":
            names[i] = analysis_names[j]
            named.add(i)
            taken.add(j)
    out: list[str] = []
    for name in names:
        k, new = 1, name
        while new in out:
            k += 1
            new = f"{name}-{k}"
        out.append(new)
    return out


def _noisy(shape: np.ndarray, freq: np.ndarray, rng: np.random.Generator) -> tuple:
    """(frequencies, shapes, damping) as measured: each shape's sign fixed (largest sensor entry
    positive), then frequency noise (n,), shape noise (n, 120) and damping drawn in that order."""
    peak = np.take_along_axis(shape, np.abs(shape).argmax(axis=1)[:, None], axis=1)
    shape = shape * np.sign(peak)
    n = shape.shape[0]
    f_test = freq * (1.0 + FREQUENCY_NOISE * rng.standard_normal(n))
    rms = np.sqrt(np.mean(shape ** 2, axis=1, keepdims=True))
    shape = shape + SHAPE_NOISE * rms * rng.standard_normal(shape.shape)
    return f_test, shape, rng.uniform(*DAMPING, n)


def gvt_dataset(modes: xr.Dataset, params: mm.X56Parameters, configuration: str,
                rng: np.random.Generator, analysis: xr.Dataset,
                suspension_rng: np.random.Generator) -> xr.Dataset:
    """The GVT of one configuration from its truth modes.

    Parameters
    ----------
    modes : xarray.Dataset
        Truth modes, ``shape(mode, dof)``, the ``N_RIGID`` suspension modes first.
    params : make_model.X56Parameters
        The truth parameters (names, grid map).
    configuration : {"efew", "fffw"}
    rng : numpy.random.Generator
        Draws the elastic modes' frequency noise (n_test,), shape noise (n_test, 120) and damping.
    analysis : xarray.Dataset
        The analysis model's modes (the pre-test analysis that names the test modes).
    suspension_rng : numpy.random.Generator
        The same draws for the suspension modes (a stream of their own: the elastic modes'
        noise is that of the files written before the suspension modes were added).

    Returns
    -------
    xarray.Dataset
        GVT Dataset (structures.gvt): the suspension modes 1 .. ``N_RIGID`` (named
        ``suspension 1`` ..), then the elastic modes ``N_RIGID + 1 ..``; 120 DOFs at analysis
        grid ids.
    """
    freq = modes["frequency"].values
    if not freq[N_RIGID - 1] < 0.5 * freq[N_RIGID]:
        raise InputError(f"truth {configuration}: suspension mode {freq[N_RIGID - 1]:.3f} Hz is not "
                         f"well below the first elastic mode {freq[N_RIGID]:.3f} Hz. Fix: soften "
                         "BUNGEE_VERTICAL.")
    elastic = modes.isel(mode=slice(N_RIGID, N_RIGID + N_TEST))
    shape = sensor_shapes(elastic, params)
    names = test_names(shape, [r["name"] for r in classify_modes(elastic, configuration, params)],
                       sensor_shapes(analysis, mm.ANALYSIS),
                       [r["name"] for r in classify_modes(analysis, configuration)])
    f_test, shape, zeta = _noisy(shape, elastic["frequency"].values, rng)
    hung = modes.isel(mode=slice(0, N_RIGID))
    f_hung, shape_hung, zeta_hung = _noisy(sensor_shapes(hung, params),
                                           hung["frequency"].values, suspension_rng)
    xyz = mm._grids(mm.ANALYSIS)
    layout = sensors()
    return make_gvt_dataset(np.concatenate([f_hung, f_test]), np.vstack([shape_hung, shape]),
                            [g for g, _, _ in layout], [c for _, c, _ in layout],
                            mode=np.arange(1, N_RIGID + 1 + f_test.size),
                            damping=np.concatenate([zeta_hung, zeta]),
                            name=[f"suspension {j}" for j in range(1, N_RIGID + 1)] + names,
                            xyz=[xyz[g] for g, _, _ in layout],
                            source=f"synthetic GVT of the X-56A-class truth model, {configuration.upper()}"
                                   " (data/x56_like/truth/make_truth.py)", units=UNITS)


#: Decimal places of the written mass properties (lb, in, lb-in^2): far below any weighing's
#: accuracy, and above the last-digit round-off that differs between machines (the sums of the
#: mass properties gave 246.08178599999994 on one, 246.081786 on another), so that the shipped
#: files are made again byte for byte.
MASS_DECIMALS = 6


def measured_mass(props) -> dict:
    """The JSON of structures.massprops.read_measured_mass from the truth's mass properties,
    rounded to :data:`MASS_DECIMALS`."""
    p = props.product_of_inertia
    i = props.inertia

    def r(value) -> float:
        return round(float(value), MASS_DECIMALS) + 0.0          # + 0.0: no -0.0

    return {"weight": r(props.weight), "cg": [r(v) for v in props.cg],
            "inertia_cg": [r(i[0, 0]), r(i[1, 1]), r(i[2, 2]), r(p["Ixy"]), r(p["Izx"]),
                           r(p["Iyz"])]}


def write_truth(out: Path = MODEL_DIR, seed: int = SEED, decks: Path | None = None) -> dict:
    """Write the GVT files, the measured mass files and ``sensors.csv`` into ``out``.

    Parameters
    ----------
    out : path
        Folder of the written files (default: the analysis model's folder).
    seed : int
    decks : path, optional
        Keep the truth decks in this folder (default: a temporary folder, removed).

    Returns
    -------
    dict
        {file name: path} of the written files.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    params = truth_parameters(seed)
    written = {"sensors.csv": write_text(sensors_csv(), out / "sensors.csv")}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(decks) if decks is not None else Path(tmp) / "truth"
        mm.write_model(folder, params)
        mm.write_model(Path(tmp) / "analysis", mm.ANALYSIS)
        for k, configuration in enumerate(mm.CONFIGURATIONS):
            modes, props = deck_modes(folder, configuration)
            analysis, _ = deck_modes(Path(tmp) / "analysis", configuration)
            gvt = gvt_dataset(modes, params, configuration, np.random.default_rng((seed, k + 1)),
                              analysis,
                              np.random.default_rng((seed, k + 1 + SUSPENSION_STREAM)))
            name = f"gvt_{configuration}.unv"
            written[name] = write_uff(gvt, out / name,
                                      title=f"X-56A-class GVT {configuration.upper()}")
            name = f"mass_{configuration}.json"
            written[name] = write_json(measured_mass(props), out / name)
    return written


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=MODEL_DIR, help="folder of the written files")
    parser.add_argument("--decks", type=Path, default=None, help="keep the truth decks here")
    parser.add_argument("--seed", type=int, default=SEED)
    args = parser.parse_args(argv)
    for path in write_truth(args.out, args.seed, args.decks).values():
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
