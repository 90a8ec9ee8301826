"""Step 1 of :func:`pipeline.diagnose.diagnose`: the configurations, the settings and the
data checks made before anything is fitted.

:class:`ConfigurationData` is one tested configuration (its analysis model, GVT, measured mass
properties), :class:`DiagnoseSettings` the workflow's settings. :func:`preflight` makes every
check that can fail: analysis modes of every configuration, pairing (MAC assignment at the
sensors, or nearest frequency without shapes), enough elastic modes and sensor DOFs, test
self-orthogonality with the SEREP analysis mass, shape noise (the test shapes' part outside the
analysis modes' span) and the mass-property residual's scales
(:func:`pipeline.diagnose.evidence.build_reference`), with the test's suspension modes set
aside (:func:`structures.suspension.without_suspension`), so that a caller (the CLI) can reject
bad data before any stage runs.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Mapping

import numpy as np
import xarray as xr
from threadpoolctl import threadpool_limits

from pipeline.diagnose.effects import KINDS
from pipeline.diagnose.evidence import SELF_ORTHOGONALITY_LIMIT, build_reference
from structures.common.errors import InputError
from structures.massprops import check_cg_inside, check_measured_mass
from structures.modal import compute_modes
from structures.model import FEModel
from structures.modes import elastic_index, rigid_index
from structures.suspension import FREQUENCY_RATIO, RIGID_SHARE, without_suspension

#: Rigid-body modes added to twice the test modes for the default analysis mode count.
N_RIGID = 6


@dataclass(frozen=True)
class ConfigurationData:
    """One tested configuration.

    Attributes
    ----------
    name : str
    model : FEModel, the analysis model (nominal).
    gvt : xarray.Dataset, :mod:`structures.gvt` layout; ``shape`` may be absent (frequency-only).
    measured_mass : mapping or None, :func:`structures.massprops.read_measured_mass` layout.
    deck : Path, the deck (messages and :func:`pipeline.diagnose.apply.write_effect_deck`).
    """

    name: str
    model: FEModel
    gvt: xr.Dataset
    measured_mass: Mapping | None
    deck: Path

    def __post_init__(self):
        if not isinstance(self.model, FEModel):
            raise InputError(f"diagnose: configuration {self.name!r}: model is a "
                             f"{type(self.model).__name__}, not an FEModel. Fix: read the deck "
                             "with structures.bdf.read_model.")
        if not isinstance(self.gvt, xr.Dataset) or "frequency" not in self.gvt:
            raise InputError(f"diagnose: configuration {self.name!r}: the GVT data has no "
                             "frequency(mode). Fix: load it with structures.gvt.load_gvt.")
        if self.measured_mass is not None:
            object.__setattr__(self, "measured_mass", check_measured_mass(
                self.measured_mass, f"configuration {self.name} measured mass"))
            check_cg_inside(self.measured_mass, self.model,
                            f"configuration {self.name} measured mass")
        object.__setattr__(self, "deck", Path(self.deck))


#: The largest value each fraction setting of :class:`DiagnoseSettings` takes: beyond them the
#: test or the model says nothing (a frequency known to 20 %, a shape's noise as large as the
#: shape, every section quantity off by half), and a value written in per cent (1 for 1 %) is
#: caught.
FRACTION_LIMITS = {"frequency_noise": 0.2, "shape_noise": 1.0, "model_scatter": 0.5}


@dataclass(frozen=True)
class DiagnoseSettings:
    """Settings of :func:`pipeline.diagnose.diagnose`.

    Attributes
    ----------
    kinds : effect kinds screened (:data:`pipeline.diagnose.effects.KINDS`).
    max_effects : look-again rounds (effects named at most).
    frequency_noise : test frequency standard deviation (fraction).
    shape_noise : test shape noise per DOF relative to the shape's RMS; None: estimated.
    holdout : every holdout-th paired mode (frequency order) of each configuration is held out.
    margin : BIC margin to name one candidate over "none" and the best of another kind (a site
        of its own kind within it makes the site uncertain, not the verdict).
    refit : candidates refitted after the screening.
    nmodes : analysis modes (None: 2 x elastic test modes + 6: suspension modes not counted).
    model_scatter : relative scatter of the nominal section and mass properties that the few
        nominal parameters cannot follow: every section quantity of every property card and
        every CONM2 errs independently by it (:mod:`pipeline.diagnose.scatter`); it sets the
        residual's covariance (its scales and the correlation between modes).
    """

    kinds: tuple = KINDS
    max_effects: int = 3
    frequency_noise: float = 0.01
    shape_noise: float | None = None
    holdout: int = 3
    margin: float = 10.0
    refit: int = 6
    nmodes: int | None = None
    model_scatter: float = 0.03

    def __post_init__(self):
        kinds = (self.kinds,) if isinstance(self.kinds, str) else tuple(self.kinds)
        bad = [k for k in kinds if k not in KINDS]
        if bad or not kinds:
            raise InputError(f"diagnose: kinds {bad or '[]'} not in {list(KINDS)}. Fix: list some "
                             "of them.")
        repeated = sorted({k for k in kinds if kinds.count(k) > 1})
        if repeated:
            raise InputError(f"diagnose: kinds {list(kinds)} list {repeated} more than once. Fix: "
                             "list each kind once.")
        object.__setattr__(self, "kinds", kinds)
        for name, low in (("max_effects", 1), ("holdout", 2), ("refit", 1)):
            value = getattr(self, name)
            if not isinstance(value, (int, np.integer)) or value < low:
                raise InputError(f"diagnose: {name} = {value!r} must be an integer >= {low}.")
        for name in ("frequency_noise", "margin"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and np.isfinite(value) and value > 0):
                raise InputError(f"diagnose: {name} = {value!r} must be a positive number.")
        for name in ("shape_noise",):
            value = getattr(self, name)
            if value is not None and not (np.isfinite(value) and value > 0):
                raise InputError(f"diagnose: {name} = {value!r} must be positive or None.")
        if not (np.isfinite(self.model_scatter) and self.model_scatter >= 0):
            raise InputError(f"diagnose: model_scatter = {self.model_scatter!r} must be >= 0.")
        for name, largest in FRACTION_LIMITS.items():
            value = getattr(self, name)
            if value is not None and value > largest:
                raise InputError(f"diagnose: {name} = {value!r} is a fraction (0.01 = 1 %) and "
                                 f"must be at most {largest:g}. Fix: write it as a fraction.")
        if self.nmodes is not None and not (isinstance(self.nmodes, (int, np.integer))
                                            and self.nmodes > 0):
            raise InputError(f"diagnose: nmodes = {self.nmodes!r} must be a positive integer.")


def preflight(configurations, settings: DiagnoseSettings = DiagnoseSettings()) -> tuple:
    """Every data check of :func:`pipeline.diagnose.diagnose` that can fail, without calibration
    or screening.

    Analysis modes of every configuration, pairing, enough elastic modes and sensor DOFs, the
    shape-noise estimate, test self-orthogonality and the measured-mass residual scales (step 1
    of :mod:`pipeline.diagnose.workflow`), so that a caller (the CLI) can reject bad data before
    any stage runs.

    Parameters
    ----------
    configurations : sequence of ConfigurationData
    settings : DiagnoseSettings

    Returns
    -------
    refs : tuple of :class:`pipeline.diagnose.evidence.Reference`, one per configuration.
    notes : tuple of str, what the data can and cannot tell.

    Raises
    ------
    InputError
        No or repeated configurations, wrong settings, too few analysis modes or sensor DOFs.
    """
    configurations = tuple(configurations)
    check_inputs(configurations, settings)
    refs, notes, _ = checked(configurations, settings)
    return refs, notes


def check_inputs(configurations: tuple, settings) -> None:
    """The checks of :func:`preflight` that need no computation: configurations given, named
    once, the settings a :class:`DiagnoseSettings`, every test frequency positive and ``nmodes``
    (when set) no fewer than any configuration's test modes.

    Raises
    ------
    InputError
        Naming the configuration, the counts and the fix.
    """
    if not configurations:
        raise InputError("diagnose: no configurations. Fix: give at least one ConfigurationData.")
    names = [c.name for c in configurations]
    if len(set(names)) != len(names):
        raise InputError(f"diagnose: configuration names {names} repeat. Fix: name each once.")
    if not isinstance(settings, DiagnoseSettings):
        raise InputError("diagnose: settings must be a DiagnoseSettings.")
    for data in configurations:
        n_test = data.gvt.sizes["mode"]
        frequency = data.gvt["frequency"].values
        if np.any(frequency <= 0.0):
            raise InputError(f"diagnose: configuration {data.name}: test modes "
                             f"{data.gvt['mode'].values[frequency <= 0.0].tolist()} have frequency "
                             "0 Hz; every measured mode, a suspension mode too, has a positive "
                             "frequency, and each is weighed by its relative error. Fix: correct "
                             "their frequency records or remove those modes from the GVT file.")
        if settings.nmodes is not None and settings.nmodes < n_test:
            raise InputError(f"diagnose: configuration {data.name}: its GVT lists {n_test} test "
                             f"modes but nmodes = {settings.nmodes} analysis modes (rigid-body "
                             f"modes among them) cannot pair them. Fix: raise [diagnose] nmodes "
                             f"to at least {n_test + N_RIGID}, or leave it out "
                             "(2 x elastic test modes + 6).")


def checked(configurations, settings) -> tuple:
    """(refs, notes, hung) of :func:`preflight`, ``hung`` each configuration's suspension modes
    (a GVT Dataset, or None)."""
    notes: list = []
    hung: list = []
    with threadpool_limits(limits=1):
        refs = _preflight(configurations, settings, notes, hung)
    return tuple(refs), tuple(notes), tuple(hung)


def _preflight(configurations, settings: DiagnoseSettings, notes: list, hung: list):
    """The references of :func:`preflight`; ``hung`` receives each configuration's suspension
    modes (a GVT Dataset, or None; attribute ``n_rigid``: the model's rigid-body modes)."""
    refs = []
    for rotation, data in enumerate(configurations):
        nmodes = settings.nmodes or 2 * data.gvt.sizes["mode"] + N_RIGID
        modes = compute_modes(data.model, nmodes)
        gvt, suspended = _without_suspension(data, modes, notes)
        if settings.nmodes is None and suspended is not None:
            nmodes = 2 * gvt.sizes["mode"] + N_RIGID          # counted on the elastic test modes
            modes = modes.isel(mode=slice(0, nmodes))
        hung.append(suspended if suspended is None else
                    suspended.assign_attrs(n_rigid=int(rigid_index(modes).size)))
        n_test = gvt.sizes["mode"]
        if elastic_index(modes).size < n_test:
            raise InputError(f"diagnose: configuration {data.name}: {n_test} test modes but only "
                             f"{elastic_index(modes).size} elastic analysis modes. Fix: raise "
                             "[diagnose] nmodes.")
        ref, facts = build_reference(
            data.name, data.model, gvt, data.measured_mass, modes,
            frequency_noise=settings.frequency_noise,
            shape_noise_value=settings.shape_noise, model_scatter=settings.model_scatter,
            holdout=settings.holdout, nmodes=nmodes, rotation=rotation)
        if settings.holdout > ref.test_frequency.size:
            raise InputError(f"diagnose: configuration {data.name}: holdout = {settings.holdout} "
                             f"but only {ref.test_frequency.size} elastic test modes: some splits "
                             "of the modes would hold none out, and nothing would judge the fits "
                             "there. Fix: set [diagnose] holdout to at most "
                             f"{ref.test_frequency.size} (3, the default, holds out every third).")
        refs.append(ref)
        if ref.has_shapes:
            notes.append(f"{data.name}: {n_test} test modes, {ref.sensor_index.size} sensor DOFs, "
                         f"shape noise {100 * facts['shape_noise']:.1f} % of the RMS (median), "
                         f"test self-orthogonality largest off-diagonal "
                         f"{_rounded(facts['self_orthogonality'])}, "
                         f"paired MAC min {min(facts['mac']):.2f}.")
            if facts["unmatched"]:
                notes.append(f"{data.name}: test modes {facts['unmatched']} have no counterpart "
                             "among the analysis modes (their shapes lie outside the modes' span "
                             "at the sensors): a local mode the model lacks.")
            if facts["self_orthogonality"] is not None and \
                    facts["self_orthogonality"] > SELF_ORTHOGONALITY_LIMIT:
                notes.append(f"{data.name}: the test modes are not orthogonal in the analysis mass "
                             f"(largest off-diagonal {facts['self_orthogonality']:.2f}): noisy or "
                             "aliased shapes, or a mass distribution the model lacks.")
        else:
            notes.append(f"{data.name}: frequency-only data ({n_test} modes): paired by nearest "
                         "frequency; the shapes cannot tell where along a symmetric structure, "
                         "nor a member from a joint at one spot.")
        if not ref.mass_scale:
            notes.append(f"{data.name}: no measured mass properties: a missing mass is seen only "
                         "through the frequencies.")
    return refs


def _without_suspension(data, modes: xr.Dataset, notes: list) -> tuple:
    """(the configuration's test modes without its suspension modes, the suspension modes or
    None) (:func:`structures.suspension.without_suspension`: shapes at the sensors, placed at
    the model's grids, that are rigid-body motions below the lowest elastic analysis frequency;
    frequency-only, modes below ``FREQUENCY_RATIO`` of it), set aside with a note. Only a model
    with rigid-body modes is hung on a suspension: a clamped one keeps every test mode."""
    gvt = data.gvt
    position = None
    if "shape" in gvt:
        grids = data.model.grids
        position = grids.xyz[grids.index(gvt["grid"].values, card="GVT sensor grid",
                                         filename=gvt.attrs.get("source") or None)]
    try:
        kept, hung = without_suspension(modes, gvt, position=position)
    except InputError as exc:
        raise InputError(f"configuration {data.name}: {exc}") from None
    if not hung.sizes["mode"]:
        return gvt, None
    f_fe = modes["frequency"].values[elastic_index(modes)]
    f = hung["frequency"].values
    why = (f"their shapes are rigid-body motions at the sensors (at least {100 * RIGID_SHARE:.0f} "
           f"% of each shape) below the lowest elastic analysis frequency, {f_fe.min():.3g} Hz"
           if "shape" in gvt else
           f"below {FREQUENCY_RATIO:g} x the lowest elastic analysis frequency, "
           f"{f_fe.min():.3g} Hz")
    notes.append(f"{data.name}: test modes {hung['mode'].values.tolist()} ({f.min():.3g}-"
                 f"{f.max():.3g} Hz) are "
                 f"suspension modes, {why}: left out of the pairing (no elastic mode of the "
                 "model matches them); with shapes they identify the suspension.")
    return kept, hung


def _rounded(value):
    """``value`` to 3 decimals, None as it is."""
    return None if value is None else round(value, 3)
