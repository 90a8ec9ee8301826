"""V-g / V-f result Datasets and the flutter file contract (DESIGN.md section 6).

One sweep gives a Dataset on (velocity, root) (or (density, root) for a PKNL density sweep) with
``damping``, ``frequency`` [Hz], ``k``, ``eigenvalue``, ``converged`` and ``eigenvector(., root, mode)``,
plus the crossings on a ``crossing`` dimension. Several sweeps (Mach numbers, densities,
configurations) are stacked into ``DIR/flutter.nc`` on (case, velocity, root) and their crossings
listed in ``DIR/summary.json``.
"""
from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import xarray as xr

from flutter.crossings import Crossing
from structures.netcdf import write_dataset

KINDS = ("flutter", "divergence")


def normalise_eigenvectors(u: np.ndarray) -> np.ndarray:
    """Scale each eigenvector so its largest-magnitude component is 1 + 0i (as Nastran prints).

    Parameters
    ----------
    u : ndarray, shape (..., n)

    Returns
    -------
    ndarray, shape (..., n)
    """
    u = np.asarray(u, dtype=complex)
    idx = np.abs(u).argmax(axis=-1)
    big = np.take_along_axis(u, idx[..., None], axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(big != 0, u / np.where(big == 0, 1, big), u)


def vg_dataset(p: np.ndarray, u: np.ndarray, damping: np.ndarray, converged: np.ndarray,
               velocity: np.ndarray, density: np.ndarray, mach: np.ndarray, *, b: float,
               modes: tuple, sweep: str = "velocity", method: str = "PK",
               attrs: dict | None = None) -> xr.Dataset:
    """Build the V-g / V-f Dataset of one sweep.

    Parameters
    ----------
    p : ndarray, shape (npts, nroot) complex
        Eigenvalues p = omega (gamma + i).
    u : ndarray, shape (npts, nroot, nmode) complex
        Eigenvectors in modal coordinates.
    damping : ndarray, shape (npts, nroot)
        g (2 gamma; Nastran's decay rate for real roots).
    converged : ndarray of bool, shape (npts, nroot)
    velocity, density, mach : ndarray, shape (npts,)
    b : float
        Reference semichord (REFC / 2) for k = omega b / V.
    modes : tuple of int
        Mode ids.
    sweep : {"velocity", "density"}
        Name of the sweep dimension.
    """
    omega = np.abs(p.imag)
    dim = sweep
    ds = xr.Dataset(
        {
            "damping": ((dim, "root"), damping, {"units": "1", "long_name": "damping g = 2 gamma"}),
            "frequency": ((dim, "root"), omega / (2 * np.pi), {"units": "Hz"}),
            "k": ((dim, "root"), omega * b / velocity[:, None],
                  {"units": "1", "long_name": "reduced frequency k = omega b / V, b = refc/2"}),
            "eigenvalue": ((dim, "root"), p, {"units": "rad/s", "long_name": "p = omega (gamma + i)"}),
            "eigenvector": ((dim, "root", "mode"), normalise_eigenvectors(u),
                            {"units": "1", "long_name": "modal coordinates, largest = 1"}),
            "converged": ((dim, "root"), np.asarray(converged, dtype=bool)),
        },
        coords={
            dim: np.asarray(velocity if sweep == "velocity" else density, dtype=float),
            "root": np.arange(1, p.shape[1] + 1),
            "mode": np.asarray(modes, dtype=int),
        },
        attrs={"method": method, "refc": 2.0 * b, "sweep": sweep,
               "conventions": "p = omega (gamma + i), g = 2 gamma, k = omega b / V, b = refc/2; "
                              "real roots: g = p refc / (V ln 2) (Nastran)",
               **(attrs or {})},
    )
    other = {"velocity": ("density", density), "density": ("velocity", velocity)}[sweep]
    ds = ds.assign_coords({other[0]: (dim, np.asarray(other[1], dtype=float)),
                           "mach": (dim, np.asarray(mach, dtype=float))})
    ds["velocity"].attrs["units"] = "model length/time"
    ds["density"].attrs["units"] = "model mass/length^3"
    return ds


def attach_crossings(ds: xr.Dataset, crossings: list[Crossing],
                     eigenvectors: np.ndarray | None = None) -> xr.Dataset:
    """Add the crossings of a sweep on a ``crossing`` dimension.

    Parameters
    ----------
    ds : xarray.Dataset
        The sweep Dataset.
    crossings : list of Crossing
    eigenvectors : ndarray, shape (ncrossing, nmode), optional
        Eigenvector of each root at its crossing (stored as ``crossing_eigenvector``).
    """
    n = len(crossings)
    if eigenvectors is not None:
        ds = ds.assign(crossing_eigenvector=(("crossing", "mode"),
                                             normalise_eigenvectors(eigenvectors)))
    get = lambda name, dtype: np.array([getattr(c, name) for c in crossings], dtype=dtype)  # noqa: E731
    return ds.assign({
        "crossing_root": ("crossing", get("root", int)),
        "crossing_velocity": ("crossing", get("velocity", float)),
        "crossing_density": ("crossing", get("density", float)),
        "crossing_mach": ("crossing", get("mach", float)),
        "crossing_frequency": ("crossing", get("frequency", float), {"units": "Hz"}),
        "crossing_kind": ("crossing", np.array([c.kind for c in crossings], dtype=object)
                          if n else np.array([], dtype=object)),
        "crossing_converged": ("crossing", get("converged", bool)),
    })


def crossings_of(ds: xr.Dataset) -> list[dict]:
    """The crossings stored in a sweep Dataset as summary.json entries."""
    if "crossing_root" not in ds:
        return []
    out = []
    for i in range(ds.sizes.get("crossing", 0)):
        out.append({"mach": float(ds.crossing_mach[i]), "density": float(ds.crossing_density[i]),
                    "velocity": float(ds.crossing_velocity[i]),
                    "frequency": float(ds.crossing_frequency[i]),
                    "root": int(ds.crossing_root[i]), "kind": str(ds.crossing_kind.values[i]),
                    "converged": bool(ds.crossing_converged[i])})
    return out


def stack_cases(sweeps: list[xr.Dataset], labels: list[dict]) -> xr.Dataset:
    """Stack sweeps into the flutter.nc layout (case, velocity, root) and (case, velocity, root, mode).

    Parameters
    ----------
    sweeps : list of xarray.Dataset
        Results of :func:`flutter.pk.pk_solve` (any sweep kind; same roots and modes).
    labels : list of dict
        Per case: ``mach``, ``density`` (or ``altitude``), ``configuration``.

    Returns
    -------
    xarray.Dataset
        ``velocity`` is a point index; ``velocity_value``, ``density_value``, ``mach_value`` hold the
        flight point of each (case, velocity) (NaN padded when sweeps differ in length).
    """
    npts = max(s.sizes[s.attrs["sweep"]] for s in sweeps)
    nc = len(sweeps)
    nroot, nmode = sweeps[0].sizes["root"], sweeps[0].sizes["mode"]

    def padded(name, shape, dtype, fill):
        out = np.full((nc, npts) + shape, fill, dtype=dtype)
        for c, s in enumerate(sweeps):
            vals = s[name].transpose(s.attrs["sweep"], ...).values
            out[c, :vals.shape[0]] = vals
        return out

    dims3 = ("case", "velocity", "root")
    ds = xr.Dataset(
        {name: (dims3, padded(name, (nroot,), dt, fill), sweeps[0][name].attrs)
         for name, dt, fill in (("damping", float, np.nan), ("frequency", float, np.nan),
                                ("k", float, np.nan), ("eigenvalue", complex, np.nan),
                                ("converged", bool, False))},
        coords={"case": np.arange(nc), "velocity": np.arange(npts),
                "root": sweeps[0]["root"].values, "mode": sweeps[0]["mode"].values},
        attrs={"layout": "velocity is the point index of each case's sweep; flight point in "
                         "velocity_value / density_value / mach_value",
               "conventions": sweeps[0].attrs.get("conventions", "")},
    )
    ds["eigenvector"] = (dims3 + ("mode",), padded("eigenvector", (nroot, nmode), complex, np.nan),
                         sweeps[0]["eigenvector"].attrs)
    for name in ("velocity", "density", "mach"):
        ds[f"{name}_value"] = (("case", "velocity"), padded(name, (), float, np.nan),
                               sweeps[0][name].attrs)
    ds["method"] = ("case", np.array([s.attrs.get("method", "") for s in sweeps], dtype=str))
    for key in ("mach", "density", "altitude", "configuration"):
        vals = [lab.get(key) for lab in labels]
        if any(v is not None for v in vals):
            if key == "configuration":
                arr = np.array(["" if v is None else str(v) for v in vals], dtype=str)
            else:
                arr = np.array([np.nan if v is None else float(v) for v in vals], dtype=float)
            ds = ds.assign_coords({f"case_{key}": ("case", arr)})
    return ds


def write_flutter(out_dir: str | os.PathLike, sweeps: list[xr.Dataset], labels: list[dict]) -> Path:
    """Write ``DIR/flutter.nc`` and ``DIR/summary.json`` (DESIGN.md section 6).

    Returns
    -------
    Path
        The output directory.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    ds = stack_cases(sweeps, labels)
    write_dataset(ds, out_dir / "flutter.nc")
    summary = []
    for c, s in enumerate(sweeps):
        for entry in crossings_of(s):
            entry["case"] = c
            if labels[c].get("configuration") is not None:
                entry["configuration"] = str(labels[c]["configuration"])
            summary.append(entry)
    tmp = out_dir / ".summary.json.tmp"
    tmp.write_text(json.dumps(summary, indent=2))
    os.replace(tmp, out_dir / "summary.json")
    return out_dir
