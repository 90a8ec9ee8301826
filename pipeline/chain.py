"""The one modes -> GAFs -> flutter chain, used by ``pipeline run``, ``pipeline flutter`` and the
tuning loop.

:func:`flutter_chain` reads a deck once (structures.common.nastran.read_pynastran): its FLUTTER
requests (:mod:`pipeline.flutter_cards`), or the matched points of a case's ``[flutter.matched]``
in their place (:mod:`pipeline.flight_points`), and its aerodynamic model (aero.model); computes
the GAFs of the given modes (aero.gaf) and solves flutter from them as data (:func:`flutter.solve.
solve_flutter`); then the participation of every mode in every flutter crossing
(:func:`flutter.participation.crossing_participation`), stacked as ``participation.nc``.
:func:`case_flutter` is that chain with a case's settings, :func:`deck_modes` and
:func:`configuration_modes` give the modes of a bare deck and of a case's configuration.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import xarray as xr

from aero.gaf import generalized_aero_forces, grid_aero_forces, project_gaf
from aero.model import read_aero_model
from aero.rfa import fit_rfa
from flutter.participation import crossing_participation
from flutter.results import summary_entries, write_flutter
from flutter.rigid_roots import label_results
from flutter.solve import METHODS, solve_flutter
from pipeline.case import Case, Configuration, FlutterSettings, MatchedSettings
from pipeline.flight_points import label_lines, matched_requests
from pipeline.flutter_cards import deck_damping, lmodes, read_flutter_requests
from structures.assembly import assemble
from structures.bdf import read_model
from structures.common.errors import InputError
from structures.common.files import write_dataset
from structures.common.nastran import read_pynastran
from structures.massprops import check_cg_inside, mass_properties
from structures.modal import compute_modes
from structures.units import system_of, unit_labels


def deck_modes(deck: str | os.PathLike, nmodes: int | None = None,
               mass: str = "deck") -> xr.Dataset:
    """Modes of a bare deck for its flutter solution.

    Parameters
    ----------
    deck : path
    nmodes : int, optional
        Number of modes; default PARAM LMODES, else the deck's EIGR / EIGRL (else 20).
    mass : {"deck", "consistent", "lumped"}

    Returns
    -------
    xarray.Dataset
        The modes (DESIGN.md section 6).
    """
    bdf = read_pynastran(deck)
    model = read_model(deck, parsed=bdf)
    return compute_modes(model, nmodes or lmodes(bdf), mass=mass, system=assemble(model, mass))


def configuration_modes(config: Configuration, nmodes: int | None = None) -> tuple:
    """Modes and mass properties of one configuration (its deck, nmodes and mass option).

    Parameters
    ----------
    config : pipeline.case.Configuration
    nmodes : int, optional
        Overrides the configuration's ``nmodes``.

    Returns
    -------
    (xarray.Dataset, structures.massprops.MassProperties)
        The modes (DESIGN.md section 6) and the mass properties.
    """
    model = read_model(config.deck)
    check_cg_inside(config.measured_mass, model, f"configuration {config.name}, measured_mass")
    system = assemble(model, config.mass)
    modes = compute_modes(model, nmodes or config.nmodes, mass=config.mass, system=system)
    return modes, mass_properties(model, m_basic=system.m_basic)


def configuration_correlation(config: Configuration, modes: xr.Dataset, props,
                              settings=None, primary_modes=None) -> xr.Dataset:
    """Correlation of a configuration's modes with its GVT (paper Tables 1-4), with the model's
    mass properties against the configuration's measured ones (``mass_*`` variables on the
    ``quantity`` dim) when it states them.

    Parameters
    ----------
    config : Configuration
        With a ``gvt`` file.
    modes : xarray.Dataset
        The configuration's modes (:func:`configuration_modes`).
    props : structures.massprops.MassProperties
        Its mass properties (:func:`configuration_modes`).
    settings : structures.correlation.CorrelationSettings, optional
    primary_modes : sequence of int, optional
        Primary test modes of the acceptance checks (default: all).

    Returns
    -------
    xarray.Dataset
        :func:`structures.correlation.correlate`'s Dataset (+ the mass comparison).
    """
    from structures.acceptance import DEFAULT_CRITERIA
    from structures.correlation import CorrelationSettings, correlate
    from structures.gvt import load_gvt
    from structures.massprops import compare_mass_properties

    corr = correlate(modes, load_gvt(config.gvt), settings or CorrelationSettings(),
                     DEFAULT_CRITERIA, primary_modes=primary_modes)
    if config.measured_mass:
        comparison = compare_mass_properties(props, config.measured_mass)
        corr = corr.merge(comparison.rename({v: f"mass_{v}" for v in comparison.data_vars}))
    return corr


def _gaf_ks(aero_ks: np.ndarray, requests) -> np.ndarray:
    """Reduced frequencies of the GAFs: MKAERO1's, plus the K / KE requests' own k values (they
    solve there rather than interpolate), without k = 0."""
    extra = [v for req in requests if METHODS[req.method] == "k" for v in req.values]
    ks = np.unique(np.concatenate([aero_ks, np.asarray(extra, dtype=float)]))
    return ks[ks > 0]


def _gaf_points(aero, requests, matched: MatchedSettings | None) -> tuple:
    """(machs, ks) of the GAFs the requests need: MKAERO1's Mach numbers (the matched lines'
    own with [flutter.matched]) and :func:`_gaf_ks`."""
    machs = aero.machs if matched is None else np.asarray(matched.mach, dtype=float)
    return np.asarray(machs, dtype=float), _gaf_ks(aero.ks, requests)


def _covering(grid_gaf: xr.Dataset, machs, ks, kernel: str, deck: str) -> xr.Dataset:
    """``grid_gaf`` at exactly ``machs`` x ``ks`` (it must hold them, with the same kernel)."""
    have_m, have_k = grid_gaf["mach"].values, grid_gaf["k"].values
    im = [int(np.flatnonzero(np.isclose(have_m, m, rtol=0, atol=1e-9))[0])
          for m in machs if np.isclose(have_m, m, rtol=0, atol=1e-9).any()]
    ik = [int(np.flatnonzero(np.isclose(have_k, k, rtol=1e-12, atol=0))[0])
          for k in ks if np.isclose(have_k, k, rtol=1e-12, atol=0).any()]
    if len(im) != len(machs) or len(ik) != len(ks) or grid_gaf.attrs.get("method") != kernel:
        raise InputError(f"deck {deck}: the grid GAFs given (Mach {have_m.tolist()}, "
                         f"{have_k.size} k, {grid_gaf.attrs.get('method')} kernel) do not cover "
                         f"what its flutter requests need (Mach {np.asarray(machs).tolist()}, "
                         f"{len(ks)} k, {kernel} kernel). Fix: compute them with pipeline.chain."
                         "deck_grid_gaf for the same deck and settings.")
    return grid_gaf.isel(mach=im, k=ik)


def deck_grid_gaf(deck, *, kernel: str = "quartic", flutter_ids=None,
             structural_damping: float | None = None, units: str | None = None,
             matched: MatchedSettings | None = None, progress=None) -> xr.Dataset:
    """The deck's grid GAFs (:func:`aero.gaf.grid_aero_forces`) at the Mach numbers and reduced
    frequencies its flutter requests need (arguments as :func:`flutter_chain`): computed once,
    they serve every set of modes of that aerodynamic grid (:func:`flutter_chain`'s
    ``grid_gaf``)."""
    bdf = read_pynastran(deck)
    requests = _requests(bdf, str(deck), flutter_ids, structural_damping, matched, units)
    aero = read_aero_model(bdf)
    machs, ks = _gaf_points(aero, requests, matched)
    if progress is not None:
        progress(f"grid GAFs: {len(machs)} Mach x {ks.size} k")
    return grid_aero_forces(aero, machs, ks, method=kernel)


def _requests(bdf, deck: str, flutter_ids, structural_damping: float | None,
              matched: MatchedSettings | None, units: str | None, solver: str = "pk",
              solvers=()) -> list:
    """The deck's FLUTTER requests, or the matched lines of ``matched`` in their place, each with
    its solver."""
    if matched is None:
        return read_flutter_requests(bdf, deck, flutter_ids, structural_damping, solver, solvers)
    if flutter_ids:
        raise InputError(f"FLUTTER ids {list(flutter_ids)} (--flutter-id) and the case's "
                         "[flutter.matched] both choose the flight points. Fix: drop the FLUTTER "
                         "ids (--flutter-id) to run the matched points, or remove "
                         "[flutter.matched].")
    rhoref = float(bdf.aero.rho_ref) if bdf.aero is not None else 1.0
    return matched_requests(matched, units, deck_damping(bdf, deck, structural_damping),
                            rhoref=rhoref, source=deck, solver=solver)


def flutter_participation(results, modes: xr.Dataset, *, rigid_hz: float = 0.05,
                          units: str | None = None, configuration: str = "") -> xr.Dataset:
    """Participation of every mode in every flutter crossing of every sweep (``participation.nc``).

    Parameters
    ----------
    results : list of (dict, xarray.Dataset)
        The sweeps (:func:`flutter.solve.solve_flutter`); sweep c is ``case`` c of flutter.nc.
    modes : xarray.Dataset
        The modes the sweeps were solved on (``frequency(mode)`` Hz, ``generalized_mass(mode)``).
    rigid_hz : float
        Modes below this in-vacuo frequency (Hz) are rigid-body modes.
    units : str or None
        Unit system of the velocity and density labels (None: "model units").
    configuration : str
        Name of the configuration, stored in attrs.

    Returns
    -------
    xarray.Dataset
        ``participation(flutter_point, mode)`` [%] (sums to 100 per point; definition in
        flutter.participation), on ``flutter_point`` the coordinates ``case``, ``mach``,
        ``density``, ``velocity``, ``frequency`` [Hz], ``root`` and ``flutter_mode`` (1, 2, ... in
        order of speed within its sweep), on ``mode`` the coordinates ``rigid`` and
        ``fe_frequency`` [Hz]; attrs ``configuration``, ``units``, ``rigid_hz``. Flutter crossings
        only (classical and body-freedom, no divergence); ``flutter_point`` has length 0 when
        there is none; ``rigid_motion(mode)`` names the rigid-body modes ("plunge", "pitch",
        "" for elastic ones and modes without names). Sweeps of matched points
        (:func:`pipeline.flight_points.label_lines`) add ``altitude`` [m], ``ktas`` and ``keas``
        [kn] on ``flutter_point`` (NaN for points of other sweeps).
    """
    mass = np.diag(np.asarray(modes["generalized_mass"].values, dtype=float))
    fe_frequency = np.asarray(modes["frequency"].values, dtype=float)
    omega = 2 * np.pi * np.maximum(fe_frequency, 0.0)
    flight = {name: next(ds[f"crossing_{name}"].attrs["units"] for _, ds in results
                         if f"crossing_{name}" in ds)
              for name in ("altitude", "ktas", "keas")
              if any(f"crossing_{name}" in ds for _, ds in results)}
    rows, shares, labels_at = [], [], []
    for case, (_, ds) in enumerate(results):
        part = crossing_participation(ds, mass, omega, rigid_hz)
        for f in range(part.sizes["flutter_mode"]):
            i = int(np.flatnonzero((ds.crossing_root.values == int(part.root[f])) &
                                   (ds.crossing_velocity.values == float(part.velocity[f])))[0])
            rows.append((case, float(ds.crossing_mach[i]), float(ds.crossing_density[i]),
                         float(part.velocity[f]), float(part.frequency[f]), int(part.root[f]),
                         int(part.flutter_mode[f])))
            shares.append(part.participation.values[f])
            labels_at.append([float(ds[f"crossing_{name}"][i]) if f"crossing_{name}" in ds
                              else np.nan for name in flight])
    nmode = modes.sizes["mode"]
    P = np.array(shares, dtype=float).reshape(len(shares), nmode)
    col = list(zip(*rows)) if rows else [()] * 7
    at = np.array(labels_at, dtype=float).reshape(len(labels_at), len(flight))
    labels = unit_labels(units)
    point = "flutter_point"
    out = xr.Dataset(
        {"participation": ((point, "mode"), P, {
            "units": "%", "long_name": "modal participation",
            "definition": "100 Re(conj(u_j)(M u)_j) / (u^H M u)"})},
        coords={
            "case": (point, np.array(col[0], dtype=int),
                     {"long_name": "index of the sweep in flutter.nc's case dimension"}),
            "mach": (point, np.array(col[1], dtype=float)),
            "density": (point, np.array(col[2], dtype=float), {"units": labels.density}),
            "velocity": (point, np.array(col[3], dtype=float), {"units": labels.velocity}),
            "frequency": (point, np.array(col[4], dtype=float), {"units": "Hz"}),
            "root": (point, np.array(col[5], dtype=int)),
            "flutter_mode": (point, np.array(col[6], dtype=int),
                             {"long_name": "n-th flutter crossing of its sweep, by speed"}),
            "mode": ("mode", np.asarray(modes["mode"].values, dtype=int)),
            "rigid": ("mode", fe_frequency < rigid_hz),
            "rigid_motion": ("mode", modes["rigid_motion"].values.astype(str)
                             if "rigid_motion" in modes.coords else np.full(nmode, "")),
            "fe_frequency": ("mode", fe_frequency, {"units": "Hz",
                                                    "long_name": "in-vacuo frequency"}),
        },
        attrs={"configuration": configuration, "units": labels.system, "rigid_hz": float(rigid_hz)},
    )
    return out.assign_coords({name: (point, at[:, j], {"units": unit})
                             for j, (name, unit) in enumerate(flight.items())})


def flutter_chain(deck: str | os.PathLike, modes: xr.Dataset, *, kernel: str = "quartic",
                  flutter_ids=None, structural_damping: float | None = None,
                  rigid_hz: float = 0.05, units: str | None = None,
                  out_dir: str | os.PathLike | None = None,
                  configuration: str | None = None, progress=None,
                  matched: MatchedSettings | None = None,
                  grid_gaf: xr.Dataset | None = None, solver: str = "pk",
                  solvers=()) -> dict:
    """GAFs, flutter and participation of a deck's FLUTTER requests on ``modes``.

    Parameters
    ----------
    deck : path
        Nastran deck with aero (CAERO1/SPLINE/AERO/MKAERO1) and FLUTTER/FLFACT cards; read once.
    modes : xarray.Dataset
        The modes (DESIGN.md section 6) of the deck's structure (:func:`deck_modes`,
        :func:`configuration_modes`, a tuned model's, or imported from Nastran).
    kernel : {"quartic", "parabolic"}
        Doublet-lattice kernel integration for the GAFs.
    flutter_ids : list of int, optional
        FLUTTER cards to run (default: those selected by FMETHOD).
    structural_damping : float, optional
        g on every mode (modal viscous, as Nastran), replacing the deck's SDAMP table.
    rigid_hz : float
        In-vacuo modes below this frequency (Hz) are rigid-body modes (participation.nc).
    units : {"si", "english_in", "english_ft"}, optional
        The case's unit system, for the labels of every written number (structures.units); None
        (a bare deck): the modes' own ``units`` attribute if it names a system, else "model units".
    out_dir : path, optional
        Output folder: ``flutter.nc``, ``summary.json``, ``flutter_summary.txt``, ``vg_<n>.png``
        (:func:`flutter.results.write_flutter`), ``modes.nc``, ``gaf.nc`` and
        ``participation.nc`` (:func:`flutter_participation`). Nothing is written when None.
    configuration : str, optional
        Name stored in participation.nc (default: the deck's file stem).
    progress : callable(str), optional
        Told what is being computed (the GAFs, each FLUTTER request's sweeps).
    matched : pipeline.case.MatchedSettings, optional
        Matched-point lines (:func:`pipeline.flight_points.matched_requests`) in place of the
        deck's FLUTTER cards (with ``flutter_ids`` an error; needs ``units``); the GAFs are then
        computed at the lines' Mach numbers (MKAERO1's reduced frequencies) and every crossing
        carries its altitude, KTAS and KEAS.
    grid_gaf : xarray.Dataset, optional
        The deck's grid GAFs (:func:`deck_grid_gaf`, :func:`aero.gaf.grid_aero_forces`) at the Mach
        numbers and reduced frequencies these requests need: Q_hh is then projected on the modes
        and no doublet-lattice matrix is computed.
    solver : {"pk", "g", "p"}
        Solver of the PK / PKNL requests and matched points (:data:`flutter.solve.SOLVERS`).
    solvers : sequence of (int, str)
        Per FLUTTER id overrides of ``solver``.

    Returns
    -------
    dict
        ``summary`` (list of crossings as in summary.json), ``results`` (list of (label,
        Dataset)), ``participation`` (Dataset), ``gaf``, ``modes`` (labelled with the unit
        system), ``units`` (the system used, None for "model units").
    """
    unit_labels(units)  # an unknown name fails before any work
    deck = Path(deck)
    bdf = read_pynastran(deck)
    if units is None:
        units = system_of(modes.attrs)
    elif modes.attrs.get("units") != units:
        modes = modes.assign_attrs(units=units)  # modes.nc and the GAFs' labels name the system
    requests = _requests(bdf, str(deck), flutter_ids, structural_damping, matched, units,
                         solver, solvers)
    aero = read_aero_model(bdf)
    machs, ks = _gaf_points(aero, requests, matched)
    if grid_gaf is None:
        if progress is not None:
            progress(f"GAFs: {len(machs)} Mach x {ks.size} k, {modes.sizes['mode']} modes")
        gaf = generalized_aero_forces(aero, modes, machs, ks, method=kernel)
    else:
        gaf = project_gaf(_covering(grid_gaf, machs, ks, kernel, str(deck)), modes)
    results = solve_flutter(modes, gaf, requests, units, progress=progress, rational_fit=fit_rfa,
                            rigid_hz=rigid_hz)
    if matched is not None:
        results = label_lines(results, matched, units)
    results = label_results(results, modes, rigid_hz)
    sweeps, labels = [ds for _, ds in results], [lab for lab, _ in results]
    participation = flutter_participation(results, modes, rigid_hz=rigid_hz, units=units,
                                          configuration=configuration or deck.stem)
    if out_dir is not None:
        out_dir = Path(out_dir)
        write_flutter(out_dir, sweeps, labels, units=units, title=deck.name)
        write_dataset(modes, out_dir / "modes.nc")
        write_dataset(gaf, out_dir / "gaf.nc")
        write_dataset(participation, out_dir / "participation.nc")
    return {"summary": summary_entries(sweeps, labels), "results": results,
            "participation": participation, "gaf": gaf, "modes": modes, "units": units}


def _flutter_ids(settings: FlutterSettings, flutter_ids) -> list | None:
    """The command-line override, else the case's ids, else None (the deck's FMETHOD)."""
    return list(flutter_ids or settings.flutter_ids) or None


def case_flutter(case: Case, config: Configuration, modes: xr.Dataset,
                 out_dir: str | os.PathLike | None = None, flutter_ids=None,
                 progress=None, grid_gaf: xr.Dataset | None = None) -> dict:
    """:func:`flutter_chain` of one configuration with the case's settings.

    Kernel, FLUTTER ids (or the matched points of ``[flutter.matched]``) and structural damping
    from ``[flutter]`` (``flutter_ids``, a command-line override, replaces the case's; both empty:
    the deck's FMETHOD selection),
    ``rigid_hz`` from ``[selection]``, the unit system from ``units``. The flutter stage of
    ``pipeline run`` and ``pipeline flutter CASE`` both call this; ``progress`` and ``grid_gaf``
    as :func:`flutter_chain` (:func:`case_grid_gaf`).

    Returns
    -------
    dict
        As :func:`flutter_chain`; writes ``out_dir`` when given.
    """
    settings = case.flutter or FlutterSettings()
    return flutter_chain(config.deck, modes, kernel=settings.kernel,
                         flutter_ids=_flutter_ids(settings, flutter_ids),
                         structural_damping=settings.structural_damping,
                         rigid_hz=case.selection.rigid_hz, units=case.units, out_dir=out_dir,
                         configuration=config.name, progress=progress, matched=settings.matched,
                         grid_gaf=grid_gaf, solver=settings.solver, solvers=settings.solvers)


def case_aero_signature(case: Case, config: Configuration) -> str:
    """SHA-256 of what :func:`case_grid_gaf` computes from: the aerodynamic mesh, the splines
    (their G_kg and grid positions), REFC, SYMXZ, the Mach numbers, reduced frequencies and
    kernel. Configurations with equal signatures (e.g. two weight configurations of one airframe)
    share their grid GAFs."""
    import hashlib

    from aero.gaf import spline_matrices

    settings = case.flutter or FlutterSettings()
    bdf = read_pynastran(config.deck)
    requests = _requests(bdf, str(config.deck), _flutter_ids(settings, None),
                         settings.structural_damping, settings.matched, case.units)
    aero = read_aero_model(bdf)
    machs, ks = _gaf_points(aero, requests, settings.matched)
    digest = hashlib.sha256(repr((float(aero.refc), int(aero.symxz), settings.kernel)).encode())
    for obj in (aero.mesh, spline_matrices(aero)):
        for name, value in sorted(vars(obj).items()):
            if isinstance(value, np.ndarray):
                digest.update(name.encode())
                digest.update(np.ascontiguousarray(value).tobytes())
    for array in (machs, ks):
        digest.update(np.ascontiguousarray(array, dtype=float).tobytes())
    return digest.hexdigest()


def aero_groups(case: Case) -> dict:
    """configuration -> (the first configuration with the same :func:`case_aero_signature`, whose
    grid GAFs it uses; that signature)."""
    first, out = {}, {}
    for c in case.configurations:
        signature = case_aero_signature(case, c)
        out[c.name] = (first.setdefault(signature, c.name), signature)
    return out


def case_grid_gaf(case: Case, config: Configuration, progress=None) -> xr.Dataset:
    """:func:`deck_grid_gaf` of one configuration's deck with the case's ``[flutter]`` settings."""
    settings = case.flutter or FlutterSettings()
    return deck_grid_gaf(config.deck, kernel=settings.kernel,
                         flutter_ids=_flutter_ids(settings, None),
                         structural_damping=settings.structural_damping, units=case.units,
                         matched=settings.matched, progress=progress)


def check_case_masses(case: Case) -> None:
    """Before any computation: every configuration's measured CG lies within its deck's extent
    (:func:`structures.massprops.check_cg_inside`; its deck is read only when it states one).

    Raises
    ------
    InputError
        Naming the configuration, the coordinate, the extent and the fix.
    """
    for config in case.configurations:
        if {"x_cg", "y_cg", "z_cg"} & set(config.measured_mass):
            check_cg_inside(config.measured_mass, read_model(config.deck),
                            f"case {case.path}: configuration {config.name}, measured_mass")


def check_case_gvts(case: Case) -> None:
    """Before any computation: every configuration's GVT file reads and carries mode shapes,
    which the correlation and tuning stages pair and fit the modes by
    (:func:`structures.gvt.load_gvt`; a table of frequencies alone is the diagnosis's only).

    Raises
    ------
    InputError
        Naming the case, the configuration, the file and the fix.
    """
    from structures.gvt import load_gvt

    for config in case.configurations:
        if config.gvt is not None:
            try:
                load_gvt(config.gvt)
            except InputError as exc:
                raise InputError(f"case {case.path}, configuration {config.name}: {exc}") from None


def check_flutter_requests(case: Case, flutter_ids=None) -> None:
    """Before any computation: every configuration's deck defines the FLUTTER cards (their FLFACT
    lists and SDAMP tables) that the case's ``[flutter]`` (or the ``flutter_ids`` override)
    selects; with ``[flutter.matched]``, that no FLUTTER id is asked for and the deck's SDAMP
    selection is usable.

    Raises
    ------
    InputError
        Naming the deck, the card, its id and the fix
        (:func:`pipeline.flutter_cards.read_flutter_requests`,
        :func:`pipeline.flutter_cards.deck_damping`).
    """
    if case.flutter is None and not flutter_ids:
        return
    settings = case.flutter or FlutterSettings()
    for config in case.configurations:
        _requests(read_pynastran(config.deck), str(config.deck),
                  _flutter_ids(settings, flutter_ids), settings.structural_damping,
                  settings.matched, case.units, settings.solver, settings.solvers)
