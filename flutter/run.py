"""modes -> GAFs -> flutter for a Nastran deck: the library behind ``pipeline flutter``.

The deck's FLUTTER / FLFACT / MKAERO1 cards (read with pyNastran) are mapped to our solvers:
PK -> :func:`flutter.pk.pk_solve` (velocity sweep for every density x Mach), PKNL -> one matched
density sweep (aligned density / Mach / velocity lists), K and KE -> :func:`flutter.kmethod.k_solve`
over the FLFACT reduced frequencies. FLFACT densities are ratios to AERO RHOREF (1.0 without AERO),
negative FLFACT velocities (Nastran's "print eigenvectors" flag) are taken by magnitude. SDAMP in the
case control selects a TABDMP1 (TYPE G, CRIT or Q), applied as Nastran modal damping; PARAM LMODES
limits the number of modes.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from flutter.kmethod import k_solve
from flutter.pk import pk_solve, pk_solve_many
from flutter.results import label_units, summary_entries, write_flutter
from flutter.system import ModalSystem, StructuralDamping
from structures.common.errors import InputError, UnsupportedCardError, card_message
from structures.common.files import write_dataset
from structures.units import system_of, unit_labels

METHODS = {"PK": "pk", "PKNL": "pknl", "K": "k", "KE": "k"}


@dataclass(frozen=True)
class FlutterRequest:
    """One FLUTTER card with its FLFACT values (model units; densities absolute)."""

    sid: int
    method: str
    density: tuple
    mach: tuple
    values: tuple          # velocities (PK, PKNL) or reduced frequencies (K, KE)
    sdamp: int | None
    filename: str
    rhoref: float = 1.0    # AERO RHOREF (1.0 without AERO): the FLFACT density ratios' reference

    def __post_init__(self):
        if self.method not in METHODS:
            raise UnsupportedCardError(card_message(
                f"flutter method {self.method!r} is not supported.", card="FLUTTER",
                card_id=self.sid, filename=self.filename, fix=f"use one of {sorted(METHODS)}."))
        if self.method == "PKNL" and not (len(self.density) == len(self.mach) == len(self.values)):
            raise InputError(card_message(
                f"PKNL needs FLFACT density, Mach and velocity lists of equal length (got "
                f"{len(self.density)}, {len(self.mach)}, {len(self.values)}).", card="FLUTTER",
                card_id=self.sid, filename=self.filename, fix="give one value per flight point."))


def _param(bdf, name):
    card = bdf.params.get(name)
    return None if card is None else card.values[0]


def read_flutter_requests(bdf, filename: str = "", flutter_ids=None) -> list[FlutterRequest]:
    """The FLUTTER cards selected by FMETHOD in the case control (all of them if none is selected).

    Parameters
    ----------
    bdf : pyNastran BDF
    filename : str
        For messages.
    flutter_ids : list of int, optional
        FLUTTER card ids to run instead of the case control's FMETHOD selection.

    Returns
    -------
    list of FlutterRequest
    """
    if not bdf.flutters:
        raise InputError(card_message("the deck has no FLUTTER card.", card="FLUTTER",
                                      filename=filename, fix="add FLUTTER/FLFACT cards and FMETHOD."))
    selected = []
    cc = bdf.case_control_deck
    glob_sdamp = None
    if cc is not None:
        for sid, sc in sorted(cc.subcases.items()):
            sdamp = sc.get_parameter("SDAMP")[0] if "SDAMP" in sc.params else None
            if sid == 0:
                glob_sdamp = sdamp
            if "FMETHOD" in sc.params:
                selected.append((int(sc.get_parameter("FMETHOD")[0]), sdamp or glob_sdamp))
    if flutter_ids is not None:
        selected = [(int(sid), glob_sdamp) for sid in flutter_ids]
    elif not selected:
        selected = [(sid, None) for sid in sorted(bdf.flutters)]
    rhoref = float(bdf.aero.rho_ref) if bdf.aero is not None else 1.0
    out = []
    for sid, sdamp in selected:
        if sid not in bdf.flutters:
            raise InputError(card_message(f"FMETHOD selects FLUTTER {sid}, which is not defined.",
                                          card="FLUTTER", card_id=sid, filename=filename,
                                          fix="add the FLUTTER card or correct FMETHOD."))
        fl = bdf.flutters[sid]
        lists = []
        for what, fid in (("density", fl.density), ("Mach", fl.mach),
                          ("velocity/k", fl.reduced_freq_velocity)):
            fid = fid if isinstance(fid, int) else fid.sid
            if fid not in bdf.flfacts:
                raise InputError(card_message(f"FLUTTER {sid} refers to FLFACT {fid} ({what}), "
                                              "which is not defined.", card="FLFACT", card_id=fid,
                                              filename=filename, fix="add the FLFACT card."))
            lists.append(np.asarray(bdf.flfacts[fid].factors, dtype=float))
        dens, mach, vals = lists
        out.append(FlutterRequest(sid=sid, method=fl.method, density=tuple(dens * rhoref),
                                  mach=tuple(mach), values=tuple(np.abs(vals)),
                                  sdamp=None if sdamp is None else int(sdamp), filename=filename,
                                  rhoref=rhoref))
    return out


def structural_damping(bdf, sdamp: int | None, filename: str = "") -> StructuralDamping:
    """TABDMP1 ``sdamp`` as modal structural damping in g units (TYPE G, CRIT: g = 2 zeta, Q: 1/Q)."""
    if sdamp is None:
        return StructuralDamping()
    if sdamp not in bdf.tables_sdamping:
        raise InputError(card_message(f"SDAMP selects TABDMP1 {sdamp}, which is not defined.",
                                      card="TABDMP1", card_id=sdamp, filename=filename,
                                      fix="add the TABDMP1 card or correct SDAMP."))
    tab = bdf.tables_sdamping[sdamp]
    y = np.asarray(tab.y, dtype=float)
    kind = str(getattr(tab, "Type", "G")).upper()
    g = {"G": y, "CRIT": 2.0 * y, "Q": 1.0 / np.where(y == 0, np.inf, y)}.get(kind)
    if g is None:
        raise UnsupportedCardError(card_message(f"TABDMP1 TYPE {kind} is not supported.",
                                                card="TABDMP1", card_id=sdamp, filename=filename,
                                                fix="use TYPE G, CRIT or Q."))
    return StructuralDamping(frequency=tuple(np.asarray(tab.x, dtype=float)), table_g=tuple(g),
                             kind="viscous")


def modal_system(modes: xr.Dataset, structural: StructuralDamping) -> ModalSystem:
    """Diagonal M_hh, K_hh of a modes Dataset (generalized mass, frequency in Hz)."""
    gm = np.asarray(modes["generalized_mass"].values, dtype=float)
    w = 2 * np.pi * np.maximum(np.asarray(modes["frequency"].values, dtype=float), 0.0)
    return ModalSystem(np.diag(gm), np.diag(gm * w * w), structural=structural,
                       modes=tuple(int(m) for m in modes["mode"].values))


def _cores() -> int:
    """Cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def solve_request(system: ModalSystem, gaf, req: FlutterRequest) -> list[tuple[dict, xr.Dataset]]:
    """Run one FLUTTER request; returns (label, result Dataset) per sweep."""
    out = []
    if METHODS[req.method] == "pk":
        V = np.unique(req.values)
        points = [(rho, m) for rho in req.density for m in req.mach]
        # the sweeps are independent: one per core (flutter.parallel)
        results = pk_solve_many(system, gaf, [(V, rho, m) for rho, m in points],
                                workers=min(len(points), _cores()))
        for (rho, m), ds in zip(points, results):
            out.append(({"mach": m, "density": rho, "configuration": f"FLUTTER {req.sid}"}, ds))
    elif METHODS[req.method] == "pknl":
        rho, mach, V = (np.asarray(x) for x in (req.density, req.mach, req.values))
        order = np.argsort(rho, kind="stable")
        ds = pk_solve(system, gaf, V[order], density=rho[order], mach=mach[order], sweep="density")
        out.append(({"mach": float(mach[0]), "configuration": f"FLUTTER {req.sid}"}, ds))
    else:
        for rho in req.density:
            for m in req.mach:
                ds = k_solve(system, gaf, np.unique(req.values), density=rho, mach=m)
                out.append(({"mach": m, "density": rho, "configuration": f"FLUTTER {req.sid}"}, ds))
    return out


def run_flutter(deck: str | os.PathLike, out_dir: str | os.PathLike | None = None, *,
                modes: xr.Dataset | None = None, gaf: xr.Dataset | None = None,
                nmodes: int | None = None, kernel: str = "quartic", flutter_ids=None,
                units: str | None = None) -> dict:
    """modes -> GAFs -> flutter for a Nastran deck; writes the flutter outputs of DESIGN.md section 6.

    Parameters
    ----------
    deck : path
        Nastran deck with structure, aero (CAERO1/SPLINE/AERO/MKAERO1) and FLUTTER/FLFACT cards.
    out_dir : path, optional
        Output folder: ``flutter.nc`` (every case, p-k and k method alike), ``summary.json``,
        ``flutter_summary.txt`` (Nastran's FLUTTER SUMMARY layout), ``vg_<case>.png``
        (:func:`flutter.results.write_flutter`), ``modes.nc`` and ``gaf.nc``. Nothing is written
        when None.
    modes, gaf : xarray.Dataset, optional
        Precomputed modes / GAFs (otherwise computed with structures.modal and aero.gaf).
    nmodes : int, optional
        Number of modes (default PARAM LMODES, else the deck's EIGR/EIGRL).
    kernel : str
        Doublet-lattice kernel integration for the GAFs.
    flutter_ids : list of int, optional
        FLUTTER cards to run (default: those selected by FMETHOD).
    units : {"si", "english_in", "english_ft"}, optional
        The case's unit system, for the labels of every written number (structures.units); None
        (a bare deck): the modes' own ``units`` attribute if it names a system, else "model units".

    Returns
    -------
    dict
        ``summary`` (list of crossings as in summary.json), ``results`` (list of (label, Dataset),
        the Datasets labelled with the unit system), ``modes``, ``gaf``, ``units`` (the system
        used, None for "model units").
    """
    from structures.common.nastran import read_pynastran

    unit_labels(units)  # an unknown name fails before any work
    deck = Path(deck)
    bdf = read_pynastran(deck)
    requests = read_flutter_requests(bdf, str(deck), flutter_ids)
    if modes is None:
        from structures.bdf import read_model
        from structures.modal import compute_modes

        lmodes = _param(bdf, "LMODES")
        modes = compute_modes(read_model(deck), nmodes or (int(lmodes) if lmodes else None))
    if units is None:
        units = system_of(modes.attrs)
    elif modes.attrs.get("units") != units:
        modes = modes.assign_attrs(units=units)  # modes.nc and the GAFs' labels name the system
    if gaf is None:
        from aero.gaf import generalized_aero_forces
        from aero.model import read_aero_model

        aero = read_aero_model(deck)
        # K / KE solve at their FLFACT k values: compute the GAFs there rather than interpolate
        extra = [v for req in requests if METHODS[req.method] == "k" for v in req.values]
        ks = np.unique(np.concatenate([aero.ks, np.asarray(extra, dtype=float)]))
        ks = ks[ks > 0]
        gaf = generalized_aero_forces(aero, modes, aero.machs, ks, method=kernel)
    results = []
    for req in requests:
        system = modal_system(modes, structural_damping(bdf, req.sdamp, str(deck)))
        for lab, ds in solve_request(system, gaf, req):
            ds = label_units(ds, units)
            ds.attrs.update(method=req.method, rhoref=req.rhoref,
                            configuration=lab["configuration"])
            results.append((lab, ds))
    summary = summary_entries([ds for _, ds in results], [lab for lab, _ in results])
    if out_dir is not None:
        out_dir = Path(out_dir)
        write_flutter(out_dir, [ds for _, ds in results], [lab for lab, _ in results],
                      units=units, title=deck.name)
        write_dataset(modes, out_dir / "modes.nc")
        write_dataset(gaf, out_dir / "gaf.nc")
    return {"summary": summary, "results": results, "modes": modes, "gaf": gaf, "units": units}
