"""Matched flight points of a case's ``[flutter.matched]`` as flutter requests.

Each Mach number M of the table is one line of ``points`` flight points, from the top of the
altitude range down to its bottom: density rho(h) and true airspeed V = M a(h) of the U.S. Standard
Atmosphere 1976 (flutter.atmosphere; :func:`flutter.matched.line_points`), converted from SI to
the model's units of the case's unit system (:meth:`flutter.atmosphere.Units.named`). The line is
one PKNL request (a p-k solution at every matched point, density increasing), which replaces the
decks' FLUTTER cards; its structural damping is the case's ``structural_damping`` or the deck's
SDAMP table (:func:`pipeline.flutter_cards.deck_damping`). The GAFs are computed at the lines'
own Mach numbers (pipeline.chain), so no Mach is interpolated.

The solved lines carry ``altitude`` [m] on their density dimension and their crossings the
altitude, KTAS and KEAS (:func:`flutter.matched.label_crossings`).
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from flutter.atmosphere import Units
from flutter.matched import label_crossings, line_points
from flutter.solve import FlutterRequest
from flutter.system import StructuralDamping
from structures.common.errors import InputError
from structures.units import UNIT_SYSTEMS


def _units(units: str | None) -> Units:
    """Model units of a named system (matched points need one: the atmosphere is in SI)."""
    if units not in UNIT_SYSTEMS:
        raise InputError(f"[flutter.matched]: the unit system {units!r} does not give the model's "
                         "units, which the US76 atmosphere (SI) is converted to. Fix: set the "
                         f"case's units to one of {', '.join(UNIT_SYSTEMS)}.")
    return Units.named(units)


def line_altitudes(matched) -> np.ndarray:
    """Altitudes of a matched line, m, from the top of the range down to its bottom.

    Parameters
    ----------
    matched : pipeline.case.MatchedSettings

    Returns
    -------
    ndarray, shape (matched.points,)
    """
    low, high = matched.altitude_range_m
    return np.linspace(high, low, matched.points)


def matched_requests(matched, units: str, damping: StructuralDamping, *, rhoref: float = 1.0,
                     source: str = "", solver: str = "pk") -> list[FlutterRequest]:
    """One PKNL request per Mach number of ``[flutter.matched]``.

    Parameters
    ----------
    matched : pipeline.case.MatchedSettings
    units : {"si", "english_in", "english_ft"}
        The case's unit system: the model's units of density and velocity.
    damping : StructuralDamping
        Structural damping of every line (:func:`pipeline.flutter_cards.deck_damping`).
    rhoref : float
        The deck's AERO RHOREF (model units), the reference of the printed density ratios.
    source : str
        The deck's file name, for messages.
    solver : {"pk", "g", "p"}
        Solver of the matched points (:data:`flutter.solve.SOLVERS`).

    Returns
    -------
    list of FlutterRequest
        Request i (sid i, named "Mach 0.160 matched line") holds the line's densities and
        velocities in model units at :func:`line_altitudes`, density increasing.

    Raises
    ------
    InputError
        ``units`` is not a named unit system.
    """
    model = _units(units)
    h = line_altitudes(matched)
    out = []
    for sid, mach in enumerate(matched.mach, start=1):
        rho, V = line_points(h, mach, model)
        out.append(FlutterRequest(sid=sid, method="PKNL", density=tuple(rho),
                                  mach=(mach,) * h.size, values=tuple(V), rhoref=rhoref,
                                  damping=damping, source=source, solver=solver,
                                  name=f"Mach {mach:.3f} matched line"))
    return out


def label_lines(results, matched, units: str) -> list[tuple[dict, xr.Dataset]]:
    """The solved lines with ``altitude`` [m] on their density dimension and the altitude, KTAS
    and KEAS of every crossing (:func:`flutter.matched.label_crossings`).

    Parameters
    ----------
    results : list of (dict, xarray.Dataset)
        :func:`flutter.solve.solve_flutter` of :func:`matched_requests`, one sweep per line.
    matched : pipeline.case.MatchedSettings
    units : {"si", "english_in", "english_ft"}

    Returns
    -------
    list of (dict, xarray.Dataset)
    """
    model = _units(units)
    h = line_altitudes(matched)
    out = []
    for lab, ds in results:
        ds = ds.assign_coords(altitude=("density", h, {"units": "m",
                                                       "long_name": "geometric altitude (US76)"}))
        out.append((lab, label_crossings(ds, model)))
    return out
