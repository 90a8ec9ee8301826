"""Atomic writing of results: netCDF4 Datasets (complex values supported), text, JSON, folders.

Every stage writes through :func:`write_dataset` / :func:`write_text` / :func:`write_json`, which
write a temporary file beside the target and rename it, so an interrupted run never leaves a
half-written result behind. A command that writes several files into a folder does so inside
:func:`staged_folder`, so that a failure leaves none of them. :func:`check_output` rejects an output
path that cannot be written before anything is computed.
"""
from __future__ import annotations

import json
import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path

import xarray as xr

from structures.common.errors import InputError


def _atomic(path: Path, write) -> Path:
    """Call ``write(tmp)`` on a temporary file beside ``path``, then rename it to ``path``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise
    return path


def write_dataset(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Write ``ds`` to ``path`` as netCDF4 atomically (temp file + rename).

    Complex variables are stored with netCDF4's ``auto_complex`` compound type.
    """
    return _atomic(Path(path), lambda tmp: ds.to_netcdf(tmp, engine="netcdf4", auto_complex=True))


def write_text(text: str, path: str | os.PathLike) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically (temp file + rename)."""
    return _atomic(Path(path), lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


def write_json(obj, path: str | os.PathLike) -> Path:
    """Write ``obj`` as indented JSON to ``path`` atomically (non-JSON values as ``str``)."""
    return write_text(json.dumps(obj, indent=2, default=str) + "\n", path)


def read_dataset(path: str | os.PathLike) -> xr.Dataset:
    """Read a Dataset written by :func:`write_dataset` fully into memory."""
    path = Path(path)
    if not path.exists():
        raise InputError(f"file {path}: no such result file. Fix: check the path or re-run the stage "
                         "that writes it.")
    try:
        with xr.open_dataset(path, engine="netcdf4", auto_complex=True) as ds:
            return ds.load()
    except (OSError, ValueError) as exc:  # netCDF4 / HDF5 signal a damaged file this way
        raise InputError(f"file {path}: not a readable netCDF4 file ({exc}). Fix: give a file "
                         "written by this project (pipeline modes/correlate/flutter --out) or "
                         "re-run the stage that writes it.") from exc


def check_output(path: str | os.PathLike, *, folder: bool, option: str = "--out") -> Path:
    """Check before any computation that ``path`` can be written as a file or as a folder.

    Parameters
    ----------
    path : path
        The output file (``folder=False``) or folder (``folder=True``); it may not exist yet.
    folder : bool
        Whether a folder is needed.
    option : str
        The option or key that gave the path, for the message.

    Raises
    ------
    InputError
        A file where a folder is needed (or the reverse), a parent that is a file, or a location
        this process may not write.
    """
    path = Path(path)
    if path.exists() and path.is_dir() != folder:
        what, other = ("a folder", "a file") if folder else ("a file", "a folder")
        raise InputError(f"{option} {path}: is {other}, but {what} is needed. Fix: give a new path "
                         f"or {what}.")
    parent = path if path.exists() and folder else path.parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise InputError(f"{option} {path}: {parent} is a file, not a folder. Fix: give a path in "
                         "a folder.")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"{option} {path}: the folder {parent} is not writable. Fix: give a path "
                         "in a folder you may write to.")
    return path


@contextmanager
def staged_folder(path: str | os.PathLike):
    """Write a folder's files all or nothing.

    Yields a temporary folder beside ``path``; when the block ends normally its files are moved
    into ``path`` (created if needed; existing files of the same names are replaced). When the block
    raises (including KeyboardInterrupt), the temporary folder and every parent folder this call
    created are removed, so the failed command leaves no new file behind.
    """
    path = Path(path)
    created = [p for p in (path, *path.parents) if not p.exists()][::-1]
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", dir=path.parent))
    try:
        yield tmp
        if not path.exists():
            os.replace(tmp, path)
            return
        for src in sorted(tmp.rglob("*")):
            if src.is_file():
                dst = path / src.relative_to(tmp)
                dst.parent.mkdir(parents=True, exist_ok=True)
                os.replace(src, dst)
        shutil.rmtree(tmp)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        for folder in reversed(created[:-1] if path in created else created):
            if folder.exists() and not any(folder.iterdir()):
                folder.rmdir()
        raise
