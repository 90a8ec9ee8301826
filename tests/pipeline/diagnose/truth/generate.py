"""``make_case``: one blind-study case -- analysis decks, synthetic GVT and weighing of a hidden truth.

The truth of a case is the analysis structure with nuisance scatter (``effects.scatter``: PBAR
fields 3 %, CONM2 2 %, E 1 %, clipped at 2 sigma) and one hidden effect of the requested kind
(``effects.draw`` / ``effects.apply``). The effect is re-drawn (up to ``ATTEMPTS`` times, from
the same seeded stream) until it shifts the largest of the measured elastic frequencies of the
first configuration by ``SHIFT_RANGE`` (a few %: visible above 1 % noise, not a different
aircraft); the draw closest to the range is kept when none falls in it.

The GVT follows ``data/x56_like/truth/make_truth.py``: the truth's elastic modes 7 .. 6 + N_TEST
(1 .. N_TEST on the clamped wing box and WINDY wing; solved by our solver, on the wing box by
MYSTRAN, ``wingbox.mystran_modes``) at the 120 sensors (analysis grid ids and positions), each
shape's sign fixed (largest entry positive), then frequencies x (1 + 1 % N(0, 1)), shapes +
N(0, (5 % of the mode's RMS)^2) per DOF (``noise``: other levels scale the same draws), damping
zeta uniform 1-2 %; UFF 15 + 55. The weighing is the truth's exact
weight, CG and inertia about the CG (``make_truth.measured_mass``).

Random streams: the scatter ``numpy.random.default_rng((seed, structure))`` (the same aircraft for
every kind of one seed, so cases differ by their effect alone), the effect and the noise of
configuration i ``default_rng((seed, structure, kind, 1))`` and ``(..., 2 + i)``.
"""
from __future__ import annotations

import json
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import xarray as xr

from structures.bdf import read_model
from structures.common.errors import InputError
from structures.common.files import write_json, write_text
from structures.common.nastran import read_pynastran
from structures.gvt import make_gvt_dataset, write_uff
from structures.massprops import mass_properties
from structures.modal import compute_modes

from . import effects, frame, windy, wingbox, x56

#: The library's kinds (the contract's ``KINDS``, spelled out: the generator never imports the
#: workflow).
KINDS = ("lumped_mass", "joint_flexibility", "member_taper", "member_curvature",
         "boundary_stiffness")
TRUTH_KINDS = KINDS + ("none", "outside")
STRUCTURES = ("x56", "frame", "wingbox", "windy")
#: The truth kinds each structure can hold.
STRUCTURE_KINDS = {"x56": TRUTH_KINDS, "frame": TRUTH_KINDS, "wingbox": wingbox.KINDS,
                   "windy": windy.KINDS}
#: Rigid-body modes of the free-free structures (the frame, the X-56).
N_RIGID = 6
SHIFT_RANGE = (0.03, 0.15)
ATTEMPTS = 30
FREQUENCY_NOISE, SHAPE_NOISE, DAMPING = 0.01, 0.05, (0.01, 0.02)
#: The sixth (suspension) mode must stay below this fraction of the first elastic one.
SUSPENSION_RATIO = 0.8
#: Stream of the suspension draw (``make_case(suspension=True)``); its modes' noise takes the
#: streams after it.
SUSPENSION_STREAM = 10
#: With ``decks``: the JSON file there naming each configuration's truth deck.
TRUTH_DECKS = "truth_decks.json"


@dataclass(frozen=True)
class Structure:
    """A blind-study structure written for one case: its analysis and truth-start decks."""

    units: str
    n_test: int
    n_rigid: int
    sensors: list                # (grid, component) of the GVT
    decks: dict                  # configuration -> analysis deck
    starts: dict                 # configuration -> the truth's starting deck
    solve: Callable              # (truth deck, number of modes) -> modes Dataset
    brace_grids: tuple | None = None    # grids an outside brace may join (None: the bars')
    outside: str = "brace"              # the form of its outside effect (``effects.OUTSIDE``)


def _our_modes(path: Path, nmodes: int) -> xr.Dataset:
    return compute_modes(read_model(path), nmodes)


def _structure(structure: str, folder: Path, work: Path) -> Structure:
    """The structure's decks written: analysis decks into ``folder``, truth starts into
    ``work``."""
    if structure == "frame":
        deck = frame.write_frame(folder)
        return Structure(frame.UNITS, frame.N_TEST, N_RIGID, frame.sensors(), {"frame": deck},
                         {"frame": deck}, _our_modes)
    if structure == "wingbox":
        deck = wingbox.write_wingbox(folder)
        return Structure(wingbox.UNITS, wingbox.N_TEST, wingbox.N_RIGID, wingbox.sensors(),
                         {"wingbox": deck}, {"wingbox": deck}, wingbox.mystran_modes,
                         outside=wingbox.OUTSIDE)
    if structure == "windy":
        deck = windy.write_windy(folder)
        return Structure(windy.UNITS, windy.N_TEST, windy.N_RIGID, windy.sensors(),
                         {"windy": deck}, {"windy": windy.truth_start(deck, work)}, _our_modes,
                         windy.brace_grids())
    decks = x56.write_analysis(folder)
    starts = {c: x56.write_structure(work, c) for c in x56.CONFIGURATIONS}
    return Structure(x56.UNITS, x56.N_TEST, N_RIGID, x56.sensors(), decks, starts, _our_modes)


def _truth_modes(start: Path, work: Path, effect, rng_seed, st: Structure, springs=None):
    """Scatter + effect (+ the suspension ``springs``, :func:`effects.hang`) on the start deck,
    written to ``work / truth_<start>`` and solved by the structure's truth solver: (modes, mass
    properties)."""
    bdf = read_pynastran(start)
    effects.scatter(bdf, np.random.default_rng(rng_seed))
    if effect is not None:
        effects.apply(bdf, effect)
    if springs:
        effects.hang(bdf, springs)
    path = work / f"truth_{start.stem}.bdf"
    bdf.write_bdf(str(path), enddata=True)
    return st.solve(path, st.n_rigid + st.n_test + 8), mass_properties(read_model(path))


def _shift(base: np.ndarray, modes: xr.Dataset, st: Structure) -> float:
    """Largest |f / f_base - 1| over the measured elastic modes (sorted frequencies)."""
    f = modes["frequency"].values[st.n_rigid:st.n_rigid + st.n_test]
    return float(np.max(np.abs(f / base - 1.0)))


def _suspended(modes: xr.Dataset, st: Structure) -> bool:
    """The highest rigid-body (suspension) mode well below the first elastic one (True when
    the structure is clamped)."""
    if st.n_rigid == 0:
        return True
    f = modes["frequency"].values
    return bool(f[st.n_rigid - 1] < SUSPENSION_RATIO * f[st.n_rigid])


def measured(modes: xr.Dataset, sensors, rng, noise: tuple) -> tuple:
    """(frequencies, shapes, damping) of ``modes`` at the sensors as a test gives them: each
    shape's sign fixed (largest entry positive), then frequency and shape noise and damping."""
    key = {(int(g), int(c)): j for j, (g, c) in
           enumerate(zip(modes["grid"].values, modes["component"].values))}
    n = modes.sizes["mode"]
    shape = modes["shape"].values[:, [key[s] for s in sensors]]
    peak = np.take_along_axis(shape, np.abs(shape).argmax(axis=1)[:, None], axis=1)
    shape = shape * np.sign(peak)
    f = modes["frequency"].values * (1.0 + noise[0] * rng.standard_normal(n))
    rms = np.sqrt(np.mean(shape ** 2, axis=1, keepdims=True))
    shape = shape + noise[1] * rms * rng.standard_normal(shape.shape)
    return f, shape, rng.uniform(*DAMPING, n)


def _gvt(modes: xr.Dataset, st: Structure, analysis_xyz: dict, rng, title: str,
         noise: tuple, hung_rng=None) -> xr.Dataset:
    """Noisy GVT of the truth's elastic modes at the sensors (module docstring); ``noise`` is
    (frequency, shape) noise. With ``hung_rng`` the truth hangs on a suspension and its
    ``n_rigid`` suspension modes are listed first (modes 1 ..), their noise drawn from
    ``hung_rng`` (the elastic modes' noise is that of the case without a suspension)."""
    sensors, n_test = st.sensors, st.n_test
    f, shape, zeta = measured(modes.isel(mode=slice(st.n_rigid, st.n_rigid + n_test)),
                               sensors, rng, noise)
    first = st.n_rigid + 1
    if hung_rng is not None:
        hung = measured(modes.isel(mode=slice(0, st.n_rigid)), sensors, hung_rng, noise)
        f, shape, zeta = (np.concatenate([a, b]) for a, b in zip(hung, (f, shape, zeta)))
        first = 1
    return make_gvt_dataset(f, shape, [g for g, _ in sensors], [c for _, c in sensors],
                            mode=np.arange(first, first + f.size),
                            damping=zeta, xyz=[analysis_xyz[g] for g, _ in sensors], source=title,
                            units=st.units)


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_jsonable(v) for v in value]
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (np.floating,)):
        return float(value)
    return value


def _case_toml(name: str, units: str, configurations, diagnose: dict) -> str:
    lines = ["# blind-study case (tests/pipeline/diagnose/truth): the truth is in truth.json",
             f'name = "{name}"', f'units = "{units}"']
    for c, deck in configurations:
        lines += ["", "[[configurations]]", f'name = "{c}"', f'deck = "{deck.name}"',
                  f'gvt = "gvt_{c}.unv"', f'measured_mass = "mass_{c}.json"']
    if diagnose:
        lines += ["", "[diagnose]"] + [f"{k} = {json.dumps(v)}" for k, v in diagnose.items()]
    return "\n".join(lines) + "\n"


def make_case(structure: str, kind: str, seed: int, out, *, decks=None,
              diagnose: dict | None = None,
              noise: tuple = (FREQUENCY_NOISE, SHAPE_NOISE), suspension: bool = False) -> Path:
    """Write a blind-study case into ``out``; returns the path of its ``case.toml``.

    Parameters
    ----------
    structure : one of ``STRUCTURES`` ("frame": one configuration; "x56": EFEW and FFFW)
    kind : one of ``TRUTH_KINDS``
    seed : int, every random draw (deterministic)
    out : folder (created)
    decks : folder, optional
        Keep the truth decks there (``truth_<start deck>.bdf``, one per configuration, named
        per configuration in :data:`TRUTH_DECKS`).
    diagnose : dict, optional
        A ``[diagnose]`` table for the case file (e.g. ``{"max_effects": 1}``); none by default.
    noise : (frequency, shape), the standard deviations of the test's noise (fractions: of each
        frequency, of each shape's RMS per DOF); the same draws scaled (a case at other noise is
        the same case otherwise).
    suspension : bool, the truth is tested on three bungees (:func:`effects.draw_suspension`,
        stream ``(seed, structure, kind, SUSPENSION_STREAM)``) and its GVT lists the suspension
        modes first (their noise from stream ``SUSPENSION_STREAM + 1 + i``); the effect, the
        scatter and the elastic modes' noise are drawn as without it. Free structures only.

    Returns
    -------
    Path
        ``out / "case.toml"``; beside it the analysis decks, ``gvt_<configuration>.unv``,
        ``mass_<configuration>.json`` and ``truth.json`` (``kind``, ``grids``, ``elements``,
        ``properties``, ``size`` in the analysis deck's ids, ``neighbours``, ``structure``,
        ``seed``, ``parameters``, ``max_frequency_shift``, ``noise``).
    """
    if structure not in STRUCTURES:
        raise InputError(f"structure {structure!r}; valid: {', '.join(STRUCTURES)}.")
    if kind not in TRUTH_KINDS:
        raise InputError(f"kind {kind!r}; valid: {', '.join(TRUTH_KINDS)}.")
    if kind not in STRUCTURE_KINDS[structure]:
        raise InputError(f"kind {kind!r} on the {structure}: it has no element such an effect "
                         f"acts on; valid there: {', '.join(STRUCTURE_KINDS[structure])}.")
    noise = tuple(float(v) for v in noise)
    if len(noise) != 2 or not all(0.0 <= v < 1.0 for v in noise):
        raise InputError(f"noise {noise}: give (frequency, shape) standard deviations as "
                         "fractions in [0, 1).")
    if suspension and structure in ("wingbox", "windy"):
        raise InputError(f"suspension: the {structure} is clamped; valid for: frame, x56.")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    streams = (int(seed), STRUCTURES.index(structure), TRUTH_KINDS.index(kind))
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp) if decks is None else Path(decks)
        work.mkdir(parents=True, exist_ok=True)
        st = _structure(structure, out, work)
        starts, n_test = st.starts, st.n_test
        first = next(iter(starts))
        analysis = read_pynastran(starts[first])
        topo = effects.topology(analysis)
        scatter = streams[:2]
        base = _truth_modes(starts[first], work, None, scatter, st)
        springs = None
        if suspension:
            springs = effects.draw_suspension(
                topo, np.random.default_rng((*streams, SUSPENSION_STREAM)),
                float(base[0]["frequency"].values[st.n_rigid]), base[1].mass)
            base = _truth_modes(starts[first], work, None, scatter, st, springs)
        f_base = base[0]["frequency"].values[st.n_rigid:st.n_rigid + n_test]
        rng = np.random.default_rng((*streams, 1))
        chosen, shift, truth = effects.Effect("none"), 0.0, {first: base}
        if kind != "none":
            best = None
            for _ in range(ATTEMPTS):
                effect = effects.draw(kind, analysis, topo, rng, float(f_base[0]),
                                      st.brace_grids, st.outside)
                modes = _truth_modes(starts[first], work, effect, scatter, st, springs)
                s = _shift(f_base, modes[0], st) if _suspended(modes[0], st) else np.inf
                miss = max(SHIFT_RANGE[0] - s, s - SHIFT_RANGE[1], 0.0)
                if best is None or miss < best[0]:
                    best = (miss, effect, s, modes)
                if miss == 0.0:
                    break
            _, chosen, shift, truth[first] = best
            if decks is not None:           # the kept deck must be the chosen draw's
                truth = {}
        written = {}
        for i, (c, start) in enumerate(starts.items()):
            modes, props = truth.get(c) or _truth_modes(start, work, chosen, scatter, st,
                                                         springs)
            xyz = effects.topology(read_pynastran(start)).xyz if c != first else topo.xyz
            gvt = _gvt(modes, st, {g: tuple(float(v) for v in p) for g, p in xyz.items()},
                       np.random.default_rng((*streams, 2 + i)),
                       f"blind-study truth {structure} {kind} seed {seed}, {c}", noise,
                       np.random.default_rng((*streams, SUSPENSION_STREAM + 1 + i))
                       if suspension else None)
            write_uff(gvt, out / f"gvt_{c}.unv", title=f"{structure} {c} GVT")
            write_json(x56.measured_mass(props), out / f"mass_{c}.json")
            written[c] = st.decks[c]
        if decks is not None:
            write_json({c: f"truth_{start.stem}.bdf" for c, start in starts.items()},
                       work / TRUTH_DECKS)
    grids, els = effects.neighbours(topo, chosen.grids, chosen.elements)
    record = {"kind": kind, "structure": structure, "seed": int(seed),
              "grids": list(chosen.grids), "elements": list(chosen.elements),
              "properties": list(chosen.properties), "size": float(chosen.size),
              "size_meaning": effects.SIZE[kind],
              "neighbours": {"grids": grids, "elements": els} if kind != "none" else
              {"grids": [], "elements": []},
              "max_frequency_shift": shift, "parameters": _jsonable(chosen.params),
              "noise": {"frequency": noise[0], "shape": noise[1]},
              "suspension": None if springs is None else
              [{"grid": g, "stiffness": list(k)} for g, k in springs]}
    write_text(json.dumps(record, indent=1) + "\n", out / "truth.json")
    return write_text(_case_toml(f"{structure}_{kind}_{seed}", st.units, written.items(),
                                 diagnose or {}), out / "case.toml")
