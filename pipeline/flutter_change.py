"""Change of flutter speed and frequency per tuning stage (the paper's Table 5).

Matching rule. The flutter crossings of one sweep (one ``case`` of a configuration's flutter.nc:
one Mach number and density) are numbered by speed, 1, 2, ... (``flutter_mode`` of
participation.nc, the paper's "first / second / third flutter mode"). The n-th crossing of a sweep
at stage k is compared with the n-th crossing of the same sweep and configuration at stage 0:

    velocity_change = 100 (V_k - V_0) / V_0        frequency_change = 100 (f_k - f_0) / f_0   [%]

signed (positive: the stage flutters faster / at a higher frequency than the baseline), as the
paper's "difference = (after tuning - baseline) / baseline". A crossing present at only one of the
two stages (a sweep whose number of crossings changed) has a NaN change: the n-th crossings would
then not be the same flutter mechanism, and the table says so rather than pair unlike roots.

Matched-point sweeps (``keas`` on the participation points, pipeline.flight_points) also give the
equivalent airspeed and its change, ``keas_change = 100 (KEAS_k - KEAS_0) / KEAS_0``: along a
matched line the true airspeed is M a(h), constant wherever the speed of sound is (11-20 km in
US76), so two crossings there differ in altitude and KEAS but not in velocity.
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from structures.common.errors import InputError
from structures.units import system_of, unit_labels


def _points(part: xr.Dataset, where: str) -> tuple:
    """(case, flutter_mode, mach, density, velocity, frequency, keas) arrays of one
    participation.nc (keas NaN where the file has none)."""
    if part.sizes.get("flutter_point", 0) == 0:
        empty = np.zeros(0)
        return empty.astype(int), empty.astype(int), empty, empty, empty, empty, empty
    case = part["case"].values.astype(int)
    mode = part["flutter_mode"].values.astype(int)
    if np.any(mode < 1):
        raise InputError(f"{where}: flutter_mode {mode.min()} < 1. Fix: number the flutter "
                         "crossings of every sweep 1, 2, ... in order of speed (pipeline.chain).")
    pairs = case * (mode.max() + 1) + mode
    if np.unique(pairs).size != pairs.size:
        raise InputError(f"{where}: two flutter points share a case and flutter_mode. Fix: number "
                         "the flutter crossings of every sweep 1, 2, ... in order of speed "
                         "(pipeline.chain writes participation.nc so).")
    keas = (part["keas"].values.astype(float) if "keas" in part.coords else
            np.full(case.size, np.nan))
    return (case, mode, part["mach"].values.astype(float), part["density"].values.astype(float),
            part["velocity"].values.astype(float), part["frequency"].values.astype(float), keas)


def _per_case(case: np.ndarray, values: np.ndarray, ncase: int, name: str) -> np.ndarray:
    """One value per case from the points of every stage and configuration (NaN where the points of
    a case disagree, e.g. the density of a density sweep)."""
    lo = np.full(ncase, np.inf)
    hi = np.full(ncase, -np.inf)
    np.minimum.at(lo, case, values)
    np.maximum.at(hi, case, values)
    with np.errstate(invalid="ignore"):
        same = np.isclose(lo, hi, rtol=1e-9, atol=0.0)
    if name == "mach" and not same.all():
        bad = int(np.flatnonzero(~same)[0])
        raise InputError(f"participation.nc: case {bad} has Mach {lo[bad]:.6g} in one stage or "
                         f"configuration and {hi[bad]:.6g} in another. Fix: run every stage and "
                         "configuration with the same FLUTTER cards (the same sweeps).")
    return np.where(same, lo, np.nan)


def flutter_change(stages: list) -> xr.Dataset:
    """Flutter speed and frequency of every stage and their signed change from stage 0 (Table 5).

    Parameters
    ----------
    stages : list of dict[str, xarray.Dataset]
        ``stages[k][configuration]`` is the participation.nc Dataset of stage ``k`` (stage 0 the
        baseline): dim ``flutter_point`` with coords ``case``, ``flutter_mode``, ``mach``,
        ``density``, ``velocity``, ``frequency`` [Hz], optional ``keas`` [kn]. A configuration
        absent from a stage gives NaN for that stage.

    Returns
    -------
    xarray.Dataset
        dims ``stage`` (0 .. len(stages) - 1), ``configuration``, ``case``, ``flutter_mode``
        (1 .. the most crossings of any sweep); ``velocity``, ``frequency`` [Hz], ``keas`` [kn]
        (matched-point sweeps only) of the n-th flutter crossing of the sweep (NaN: absent),
        ``velocity_change``, ``frequency_change``, ``keas_change`` [%] relative to stage 0
        (module docstring; NaN where either is absent); coords ``mach(case)``,
        ``density(case)`` (NaN when the crossings of a case lie at different densities, i.e. a
        density sweep); attrs ``units`` (the unit system of the participation files).

    Raises
    ------
    InputError
        No stage, a case at different Mach numbers in different files, or two points with the same
        case and flutter_mode.
    """
    if not stages:
        raise InputError("flutter_change: no stage given. Fix: pass the participation Datasets of "
                         "stage 0 (the baseline) and of every tuning stage.")
    configs = list(dict.fromkeys(c for stage in stages for c in stage))
    read = {(k, c): _points(stage[c], f"stage{k}/{c}/flutter/participation.nc")
            for k, stage in enumerate(stages) for c in stage}
    all_case = np.concatenate([p[0] for p in read.values()] or [np.zeros(0, int)])
    all_mode = np.concatenate([p[1] for p in read.values()] or [np.zeros(0, int)])
    ncase = int(all_case.max()) + 1 if all_case.size else 0
    nmode = int(all_mode.max()) if all_mode.size else 0
    shape = (len(stages), len(configs), ncase, nmode)
    velocity = np.full(shape, np.nan)
    frequency = np.full(shape, np.nan)
    keas = np.full(shape, np.nan)
    for (k, c), (case, mode, _, _, v, f, e) in read.items():
        velocity[k, configs.index(c), case, mode - 1] = v
        frequency[k, configs.index(c), case, mode - 1] = f
        keas[k, configs.index(c), case, mode - 1] = e
    with np.errstate(invalid="ignore", divide="ignore"):
        dv = 100.0 * (velocity - velocity[:1]) / velocity[:1]
        df = 100.0 * (frequency - frequency[:1]) / frequency[:1]
        de = 100.0 * (keas - keas[:1]) / keas[:1]
    mach = _per_case(all_case, np.concatenate([p[2] for p in read.values()] or [np.zeros(0)]),
                     ncase, "mach")
    density = _per_case(all_case, np.concatenate([p[3] for p in read.values()] or [np.zeros(0)]),
                        ncase, "density")
    systems = {system_of(stage[c].attrs) for stage in stages for c in stage}
    labels = unit_labels(systems.pop() if len(systems) == 1 else None)
    dims = ("stage", "configuration", "case", "flutter_mode")
    return xr.Dataset(
        {"velocity": (dims, velocity, {"units": labels.velocity,
                                       "long_name": "speed of the n-th flutter crossing"}),
         "frequency": (dims, frequency, {"units": "Hz",
                                         "long_name": "frequency of the n-th flutter crossing"}),
         "velocity_change": (dims, dv, {"units": "%", "long_name": "100 (V_k - V_0) / V_0"}),
         "frequency_change": (dims, df, {"units": "%", "long_name": "100 (f_k - f_0) / f_0"}),
         "keas": (dims, keas, {"units": "kn", "long_name": "equivalent airspeed of the n-th "
                                                          "flutter crossing (NaN: not matched)"}),
         "keas_change": (dims, de, {"units": "%", "long_name": "100 (KEAS_k - KEAS_0) / KEAS_0"})},
        coords={"stage": np.arange(len(stages)), "configuration": np.array(configs, dtype=str),
                "case": np.arange(ncase), "flutter_mode": np.arange(1, nmode + 1),
                "mach": ("case", mach, {"units": "1"}),
                "density": ("case", density, {"units": labels.density})},
        attrs={"units": labels.system,
               "matching": "n-th flutter crossing (by speed) of a sweep at stage k vs the n-th at "
                           "stage 0 (paper Table 5); NaN where either is absent",
               "reference": "Pak & Truong, X-56A model tuning, Table 5"})
