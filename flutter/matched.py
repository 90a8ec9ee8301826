"""Matched-point flutter analysis through the standard atmosphere.

Three ways to make Mach, altitude (density) and velocity agree (US76 / ISA, flutter.atmosphere):
- :func:`velocity_sweep_at_altitude`: PK velocity sweep at one altitude, GAFs at one Mach; the
  crossings are labelled with their implied Mach (V / a(h)), KTAS and KEAS.
- :func:`mach_line`: constant Mach, altitude from high to low (density increasing), V = M a(h):
  every point is matched by construction (Nastran PKNL style with FLFACT density/Mach/velocity).
- :func:`matched_flutter`: at a fixed altitude, iterate the GAF Mach until the flutter speed's
  Mach V_f / a(h) equals it (fixed-point iteration, GAFs interpolated in Mach).
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from flutter.atmosphere import Units, atmosphere, flight_labels
from flutter.pk import pk_solve
from flutter.results import is_flutter
from flutter.system import ModalSystem
from structures.common.errors import InputError, SolverError


def label_crossings(ds: xr.Dataset, units: Units) -> xr.Dataset:
    """A sweep with its crossings' flight labels (:func:`flutter.atmosphere.flight_labels`):
    ``crossing_ktas``, ``crossing_keas`` [kn], ``crossing_altitude`` [m] (US76 density altitude)
    and ``crossing_matched_mach`` (V / a there) on the ``crossing`` dimension.

    Parameters
    ----------
    ds : xarray.Dataset
        A p-k sweep (flutter.pk.pk_solve) with velocity and density in model units.
    units : Units
        Model units.
    """
    n = ds.sizes.get("crossing", 0)
    if n == 0:
        return ds
    lab = flight_labels(ds.crossing_velocity.values, ds.crossing_density.values, units)
    return ds.assign(crossing_ktas=("crossing", lab["ktas"], {"units": "kn"}),
                     crossing_keas=("crossing", lab["keas"], {"units": "kn"}),
                     crossing_altitude=("crossing", lab["altitude_m"], {"units": "m"}),
                     crossing_matched_mach=("crossing", lab["mach"]))


def velocity_sweep_at_altitude(system: ModalSystem, gaf, velocity, *, altitude_m: float,
                               mach: float, units: Units = Units(), **options) -> xr.Dataset:
    """PK velocity sweep at the US76 density of ``altitude_m`` with GAFs at ``mach``.

    Parameters
    ----------
    velocity : array_like, shape (npts,)
        True airspeeds in model units (increasing).
    altitude_m : float
        Geometric altitude, m.
    mach : float
        Mach number of the GAFs.
    units : Units
        Model units.
    **options
        Passed to :func:`flutter.pk.pk_solve`.

    Returns
    -------
    xarray.Dataset
        The sweep, with ``ktas``, ``keas`` and ``matched_mach`` on the velocity dimension and the
        same labels for every crossing; attrs ``altitude_m``.
    """
    rho = float(atmosphere(altitude_m)["density"]) / units.density
    ds = pk_solve(system, gaf, velocity, density=rho, mach=mach, **options)
    a = float(atmosphere(altitude_m)["speed_of_sound"])
    V_si = ds.velocity.values * units.length
    ds = ds.assign_coords(ktas=("velocity", V_si / (1852 / 3600)),
                          keas=("velocity", V_si * np.sqrt(rho * units.density / 1.225) / (1852 / 3600)),
                          matched_mach=("velocity", V_si / a))
    ds.attrs["altitude_m"] = float(altitude_m)
    return label_crossings(ds, units)


def line_points(altitudes_m, mach: float, units: Units = Units()) -> tuple[np.ndarray, np.ndarray]:
    """Density and true airspeed of the matched points of a constant-Mach line.

    Parameters
    ----------
    altitudes_m : array_like, shape (npts,)
        Geometric altitudes, m, decreasing (so the density increases along the line).
    mach : float
    units : Units
        Model units.

    Returns
    -------
    density, velocity : ndarray, shape (npts,)
        US76 density rho(h) and V = M a(h) (US76 eqs. 42, 50), in model units.
    """
    h = np.asarray(altitudes_m, dtype=float)
    if np.any(np.diff(h) >= 0):
        raise InputError("matched line: altitudes must decrease strictly (density increasing). "
                         "Fix: sort the altitude list from high to low.")
    atm = atmosphere(h)
    return atm["density"] / units.density, mach * atm["speed_of_sound"] / units.length


def mach_line(system: ModalSystem, gaf, altitudes_m, *, mach: float, units: Units = Units(),
              **options) -> xr.Dataset:
    """Matched points at constant Mach over altitudes (density sweep, V = M a(h)).

    Parameters
    ----------
    altitudes_m : array_like, shape (npts,)
        Geometric altitudes, m, decreasing (so the density increases along the sweep).
    mach : float

    Returns
    -------
    xarray.Dataset
        PKNL sweep on ``density`` with ``altitude`` coordinate; crossings carry KEAS/KTAS/altitude.
    """
    h = np.asarray(altitudes_m, dtype=float)
    rho, V = line_points(h, mach, units)
    ds = pk_solve(system, gaf, V, density=rho, mach=mach, sweep="density", **options)
    ds = ds.assign_coords(altitude=("density", h))
    return label_crossings(ds, units)


def matched_flutter(system: ModalSystem, gaf, velocity, *, altitude_m: float, mach0: float,
                    units: Units = Units(), root: int | None = None, tol: float = 1e-4,
                    max_iter: int = 20, **options) -> dict:
    """Flutter point whose Mach, altitude and velocity agree (fixed-point iteration on Mach).

    Parameters
    ----------
    velocity : array_like
        Velocity sweep (model units) that brackets the flutter speed.
    altitude_m : float
    mach0 : float
        Starting Mach of the GAFs.
    root : int, optional
        Root to follow (default: the lowest-speed flutter crossing).
    tol : float
        Convergence tolerance on Mach.

    Returns
    -------
    dict
        ``mach``, ``velocity`` (model units), ``frequency`` (Hz), ``root``, ``altitude_m``,
        ``density`` (model units), ``ktas``, ``keas``, ``iterations``.
    """
    a = float(atmosphere(altitude_m)["speed_of_sound"])
    mach = float(mach0)
    for it in range(1, max_iter + 1):
        ds = velocity_sweep_at_altitude(system, gaf, velocity, altitude_m=altitude_m, mach=mach,
                                        units=units, **options)
        fl = [i for i in range(ds.sizes.get("crossing", 0))
              if is_flutter(ds.crossing_kind.values[i])
              and (root is None or int(ds.crossing_root[i]) == root)]
        if not fl:
            raise SolverError(f"matched_flutter: no flutter crossing at altitude {altitude_m} m, "
                              f"Mach {mach:.4f} within V = {np.min(velocity)}..{np.max(velocity)}. "
                              "Fix: widen the velocity range.")
        i = min(fl, key=lambda j: float(ds.crossing_velocity[j]))
        V = float(ds.crossing_velocity[i])
        new = V * units.length / a
        if abs(new - mach) < tol:
            return {"mach": new, "velocity": V, "frequency": float(ds.crossing_frequency[i]),
                    "root": int(ds.crossing_root[i]), "altitude_m": float(altitude_m),
                    "density": float(ds.crossing_density[i]), "ktas": float(ds.crossing_ktas[i]),
                    "keas": float(ds.crossing_keas[i]), "iterations": it}
        mach = new
    raise SolverError(f"matched_flutter: Mach did not settle within {max_iter} iterations at "
                      f"altitude {altitude_m} m (last {mach:.5f}). Fix: check the GAF Mach range.")
