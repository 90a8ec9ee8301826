"""Atomic netCDF4 reading and writing of result Datasets (complex values supported).

Every stage writes through :func:`write_dataset`, which writes a temporary file beside the target
and renames it, so an interrupted run never leaves a half-written result behind.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

import xarray as xr


def write_dataset(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Write ``ds`` to ``path`` as netCDF4 atomically (temp file + rename).

    Complex variables are stored with netCDF4's ``auto_complex`` compound type.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        ds.to_netcdf(tmp, engine="netcdf4", auto_complex=True)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise
    return path


def read_dataset(path: str | os.PathLike) -> xr.Dataset:
    """Read a Dataset written by :func:`write_dataset` fully into memory."""
    path = Path(path)
    if not path.exists():
        from structures.errors import InputError
        raise InputError(f"file {path}: no such result file. Fix: check the path or re-run the stage "
                         "that writes it.")
    with xr.open_dataset(path, engine="netcdf4", auto_complex=True) as ds:
        return ds.load()
