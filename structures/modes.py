"""The modes Dataset: the contract between the FE solver, imported Nastran results and every user.

Layout (DESIGN.md section 6): dims ``mode`` (numbered from 1) and ``dof``; variables
``frequency(mode)`` [Hz], ``shape(mode, dof)`` (translations and rotations in the BASIC frame) and
``generalized_mass(mode)``; coordinates ``grid(dof)``, ``component(dof)`` (1..6), and the basic
position ``x(dof)``, ``y(dof)``, ``z(dof)`` of each dof's grid; attrs ``source``, ``deck``, ``units``.
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from structures.common.errors import InputError
from structures.common.files import read_dataset, write_dataset

REQUIRED = ("frequency", "shape", "generalized_mass")


def modes_dataset(frequency_hz, shapes, grid_ids, grid_xyz, *, generalized_mass=None,
                  source: str, deck: str = "", units: str = "deck", extra_attrs=None) -> xr.Dataset:
    """Build a modes Dataset.

    Parameters
    ----------
    frequency_hz : (nm,) natural frequencies [Hz].
    shapes : (nm, ng * 6) mode shapes, 6 basic-frame components per grid, grid-major.
    grid_ids : (ng,) grid ids.
    grid_xyz : (ng, 3) basic positions.
    generalized_mass : (nm,), default ones (mass-normalised shapes).
    source, deck, units : provenance attributes.

    Returns
    -------
    xarray.Dataset
    """
    freq = np.asarray(frequency_hz, float)
    shapes = np.asarray(shapes, float)
    grid_ids = np.asarray(grid_ids, np.int64)
    n_g = len(grid_ids)
    if shapes.shape != (len(freq), 6 * n_g):
        raise InputError(f"mode shapes have shape {shapes.shape}, expected ({len(freq)}, {6 * n_g}). "
                         "Fix: give 6 basic-frame components per grid for every mode.")
    gm = np.ones(len(freq)) if generalized_mass is None else np.asarray(generalized_mass, float)
    xyz = np.repeat(np.asarray(grid_xyz, float), 6, axis=0)
    ds = xr.Dataset(
        {"frequency": ("mode", freq, {"units": "Hz", "long_name": "natural frequency"}),
         "shape": (("mode", "dof"), shapes,
                   {"long_name": "mode shape, basic frame", "normalisation": "Phi^T M Phi = I"
                    if generalized_mass is None else "generalized_mass"}),
         "generalized_mass": ("mode", gm, {"long_name": "Phi^T M Phi"})},
        coords={"mode": ("mode", np.arange(1, len(freq) + 1)),
                "grid": ("dof", np.repeat(grid_ids, 6)),
                "component": ("dof", np.tile(np.arange(1, 7), n_g)),
                "x": ("dof", xyz[:, 0]), "y": ("dof", xyz[:, 1]), "z": ("dof", xyz[:, 2])},
        attrs={"source": source, "deck": str(deck), "units": units, **(extra_attrs or {})})
    return ds


def check_modes(ds: xr.Dataset, where: str = "modes Dataset") -> xr.Dataset:
    """Verify the contract (variables, dims, finite values, unique mode numbers)."""
    missing = [name for name in REQUIRED if name not in ds]
    missing += [name for name in ("grid", "component") if name not in ds.coords]
    if missing:
        raise InputError(f"{where}: missing {missing}. Fix: write it with structures.modes.write_modes "
                         "or build it with modes_dataset.")
    if ds.sizes.get("mode", 0) and len(np.unique(ds["mode"].values)) != ds.sizes["mode"]:
        raise InputError(f"{where}: duplicate mode numbers. Fix: number modes uniquely.")
    if not np.all(np.isfinite(ds["shape"].values)):
        raise InputError(f"{where}: NaN or infinite values in 'shape'. Fix: check the source data.")
    return ds


def elastic_index(ds: xr.Dataset) -> np.ndarray:
    """Positions along ``mode`` of the elastic modes.

    The rigid-body modes are those that coordinate ``rigid_motion(mode)`` names
    (:func:`structures.modal.compute_modes`); a Dataset without it (an OP2's modes) has no mode
    marked rigid, and all its modes count as elastic.

    Returns
    -------
    ndarray of int, shape (n_elastic,)
    """
    if "rigid_motion" in ds.coords:
        return np.flatnonzero(ds["rigid_motion"].values.astype(str) == "")
    return np.arange(ds.sizes["mode"])


def rigid_index(ds: xr.Dataset) -> np.ndarray:
    """Positions along ``mode`` of the rigid-body modes: those :func:`elastic_index` leaves out.

    Returns
    -------
    ndarray of int, shape (n_mode - n_elastic,)
    """
    return np.setdiff1d(np.arange(ds.sizes["mode"]), elastic_index(ds))


def write_modes(ds: xr.Dataset, path) -> None:
    """Write a modes Dataset atomically to netCDF4."""
    write_dataset(check_modes(ds), path)


def read_modes(path) -> xr.Dataset:
    """Read and check a modes Dataset."""
    return check_modes(read_dataset(path), where=f"file {path}")
