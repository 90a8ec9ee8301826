"""Flutter requests and their solution from modal data and GAFs (no deck, no aerodynamics here).

A :class:`FlutterRequest` is one flutter analysis as data: the method and the flight points (the
content of a Nastran FLUTTER card with its FLFACT lists, read by :mod:`pipeline.flutter_cards`) and
the structural damping that goes with it. :func:`solve_flutter` maps each request to our solvers:
PK -> :func:`flutter.pk.pk_solve_many` (a velocity sweep for every density x Mach), PKNL -> one
matched density sweep (aligned density / Mach / velocity lists), K and KE ->
:func:`flutter.kmethod.k_solve` over the request's reduced frequencies (k = omega b / V,
b = REFC / 2). The modal matrices come from a modes Dataset (DESIGN.md section 6) and the GAFs
``Q(mach, k, mode_i, mode_j)`` from any source (aero.gaf, Nastran's OP4).
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from functools import partial

import numpy as np
import xarray as xr

from flutter.gmethod import g_solve_many
from flutter.kmethod import k_solve
from flutter.pk import pk_solve_many
from flutter.pmethod import p_solve_many
from flutter.results import label_units
from flutter.system import ModalSystem, StructuralDamping
from structures.common.errors import InputError, UnsupportedCardError, card_message

#: Nastran FLUTTER method -> our solver ("pk": velocity sweeps, "pknl": one density sweep,
#: "k": reduced-frequency sweeps).
METHODS = {"PK": "pk", "PKNL": "pknl", "K": "k", "KE": "k"}

#: How the flight points of a PK / PKNL request are solved, and the method name its results carry:
#: "pk" the p-k method (flutter.pk; name PK / PKNL as the card), "g" Chen's g-method
#: (flutter.gmethod, name G), "p" the p-method on a rational fit of the GAFs (flutter.pmethod,
#: name P-RFA). Which is the default for free-free aircraft, and why: README, "Flutter methods".
SOLVERS = {"pk": pk_solve_many, "g": g_solve_many, "p": p_solve_many}
SOLVER_NAMES = {"g": "G", "p": "P-RFA"}


@dataclass(frozen=True)
class FlutterRequest:
    """One flutter analysis (a FLUTTER card with its FLFACT values), in model units.

    Parameters
    ----------
    sid : int
        Id of the request (the FLUTTER card id); labels its sweeps "FLUTTER <sid>".
    method : {"PK", "PKNL", "K", "KE"}
    density : tuple of float, shape (nrho,)
        Absolute densities (FLFACT ratios already multiplied by ``rhoref``).
    mach : tuple of float, shape (nmach,)
    values : tuple of float, shape (nv,)
        Velocities (PK, PKNL) or reduced frequencies k = omega b / V, b = REFC / 2 (K, KE).
        PKNL needs ``density``, ``mach`` and ``values`` of equal length (one flight point each).
    rhoref : float
        Reference density of the FLFACT density ratios (AERO RHOREF; 1.0 without AERO).
    damping : StructuralDamping
        Structural damping of the modes for this request.
    source : str
        Where the request came from (e.g. the deck's file name), named in error messages.
    name : str
        Label of its sweeps (default "FLUTTER <sid>"), e.g. "Mach 0.160 matched line".
    solver : {"pk", "g", "p"}
        How a PK / PKNL request's flight points are solved (:data:`SOLVERS`); K / KE requests are
        always solved by the k-method.
    """

    sid: int
    method: str
    density: tuple
    mach: tuple
    values: tuple
    rhoref: float = 1.0
    damping: StructuralDamping = field(default_factory=StructuralDamping)
    source: str = ""
    name: str = ""
    solver: str = "pk"

    def __post_init__(self):
        if not self.name:
            object.__setattr__(self, "name", f"FLUTTER {self.sid}")
        if self.method not in METHODS:
            raise UnsupportedCardError(card_message(
                f"flutter method {self.method!r} is not supported.", card="FLUTTER",
                card_id=self.sid, filename=self.source or None,
                fix=f"use one of {sorted(METHODS)}."))
        if self.solver not in SOLVERS:
            raise InputError(card_message(
                f"flutter solver {self.solver!r} is not known.", card="FLUTTER", card_id=self.sid,
                filename=self.source or None, fix=f"use one of {sorted(SOLVERS)}."))
        if self.solver != "pk" and self.method not in ("PK", "PKNL"):
            raise InputError(card_message(
                f"solver {self.solver!r} solves PK / PKNL flight points; this request is "
                f"{self.method}.", card="FLUTTER", card_id=self.sid, filename=self.source or None,
                fix="use solver 'pk' for K / KE requests (the k-method), or make the card PK."))
        for name in ("density", "mach", "values"):
            object.__setattr__(self, name, tuple(float(x) for x in getattr(self, name)))
        if self.method == "PKNL" and not (len(self.density) == len(self.mach) == len(self.values)):
            raise InputError(card_message(
                f"PKNL needs FLFACT density, Mach and velocity lists of equal length (got "
                f"{len(self.density)}, {len(self.mach)}, {len(self.values)}).", card="FLUTTER",
                card_id=self.sid, filename=self.source or None,
                fix="give one value per flight point."))
        if not isinstance(self.damping, StructuralDamping):
            raise InputError(card_message(
                f"damping must be a flutter.system.StructuralDamping, not "
                f"{type(self.damping).__name__}.", card="FLUTTER", card_id=self.sid,
                filename=self.source or None, fix="pass StructuralDamping(...)."))


def modal_system(modes: xr.Dataset, structural: StructuralDamping) -> ModalSystem:
    """Diagonal M_hh, K_hh of a modes Dataset.

    Parameters
    ----------
    modes : xarray.Dataset
        ``generalized_mass(mode)`` and ``frequency(mode)`` [Hz] (DESIGN.md section 6).
    structural : StructuralDamping

    Returns
    -------
    ModalSystem
        M_hh = diag(m_j), K_hh = diag(m_j omega_j^2), shape (nmode, nmode), mode ids from
        ``modes["mode"]`` (negative frequencies of rounding-level rigid modes are taken as 0).
    """
    gm = np.asarray(modes["generalized_mass"].values, dtype=float)
    w = 2 * np.pi * np.maximum(np.asarray(modes["frequency"].values, dtype=float), 0.0)
    return ModalSystem(np.diag(gm), np.diag(gm * w * w), structural=structural,
                       modes=tuple(int(m) for m in modes["mode"].values))


def _cores() -> int:
    """Cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def solve_request(system: ModalSystem, gaf: xr.Dataset, req: FlutterRequest,
                  rational_fit=None, rigid_hz: float = 0.05) -> list[tuple[dict, xr.Dataset]]:
    """Solve one request on a modal system.

    Parameters
    ----------
    system : ModalSystem
        Modal matrices with the request's structural damping.
    gaf : xarray.Dataset
        ``Q(mach, k, mode_i, mode_j)`` with attrs ``refc`` (k = omega b / V, b = refc / 2).
    req : FlutterRequest
    rational_fit : callable, optional
        The rational fit of the p-method (solver "p": aero.rfa.fit_rfa, given by the caller
        because flutter/ does not import aero/).
    rigid_hz : float
        In-vacuo modes below this frequency [Hz] are rigid-body modes (their roots' start and the
        drift roots of every solver).

    Returns
    -------
    list of (dict, xarray.Dataset)
        One per sweep: the label (``mach``, ``density`` (not for PKNL), ``configuration`` =
        the request's ``name``) and the :func:`flutter.pk.pk_solve` /
        :func:`flutter.kmethod.k_solve` result.
    """
    out = []
    name = req.name
    solve = partial(SOLVERS[req.solver], rigid_hz=rigid_hz)
    if req.solver == "p":
        solve = partial(solve, fit=rational_fit)
    if METHODS[req.method] == "pk":
        V = np.unique(req.values)
        points = [(rho, m) for rho in req.density for m in req.mach]
        # the sweeps are independent: one per core (flutter.parallel)
        results = solve(system, gaf, [(V, rho, m) for rho, m in points],
                        workers=min(len(points), _cores()))
        for (rho, m), ds in zip(points, results):
            out.append(({"mach": m, "density": rho, "configuration": name}, ds))
    elif METHODS[req.method] == "pknl":
        rho, mach, V = (np.asarray(x) for x in (req.density, req.mach, req.values))
        order = np.argsort(rho, kind="stable")
        ds = solve(system, gaf, [(V[order], rho[order], mach[order])], sweep="density")[0]
        out.append(({"mach": float(mach[0]), "configuration": name}, ds))
    else:
        for rho in req.density:
            for m in req.mach:
                ds = k_solve(system, gaf, np.unique(req.values), density=rho, mach=m)
                out.append(({"mach": m, "density": rho, "configuration": name}, ds))
    return out


def solve_flutter(modes: xr.Dataset, gaf: xr.Dataset, requests, units: str | None = None,
                  progress=None, rational_fit=None,
                  rigid_hz: float = 0.05) -> list[tuple[dict, xr.Dataset]]:
    """Every request on the modes' modal system, each with its own structural damping.

    Parameters
    ----------
    modes : xarray.Dataset
        ``frequency(mode)`` [Hz], ``generalized_mass(mode)`` (DESIGN.md section 6).
    gaf : xarray.Dataset
        ``Q(mach, k, mode_i, mode_j)`` of the same modes, attrs ``refc``.
    requests : sequence of FlutterRequest
    units : {"si", "english_in", "english_ft"} or None
        Unit system whose labels the results carry (:func:`flutter.results.label_units`; None:
        "model units"). The numbers are in the model's units either way.
    progress : callable(str), optional
        Told which request is being solved.
    rational_fit : callable, optional
        The p-method's rational fit (:func:`solve_request`).
    rigid_hz : float
        Rigid-body modes' frequency bound [Hz] (:func:`solve_request`).

    Returns
    -------
    list of (dict, xarray.Dataset)
        Every sweep of every request in order, as :func:`solve_request`; each Dataset's attrs
        also hold ``method`` (the request's card method for p-k and the k-method, else the
        solver's name: G, P-RFA), ``rhoref`` and ``configuration``.
    """
    results = []
    for i, req in enumerate(requests):
        if progress is not None:
            progress(f"{req.name} ({req.method}), request {i + 1} of {len(requests)}")
        system = modal_system(modes, req.damping)
        for lab, ds in solve_request(system, gaf, req, rational_fit, rigid_hz):
            ds = label_units(ds, units)
            ds.attrs.update(method=SOLVER_NAMES.get(req.solver, req.method), rhoref=req.rhoref,
                            configuration=lab["configuration"])
            results.append((lab, ds))
    return results
