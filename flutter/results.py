"""V-g / V-f result Datasets and the flutter file contract (DESIGN.md section 6).

One sweep gives a Dataset on (velocity, root) (or (density, root) for a PKNL density sweep, or
(k, root) for the k method, whose ``velocity`` V = omega b / k is then a data variable per root)
with ``damping``, ``frequency`` [Hz], ``k``, ``eigenvalue``, ``converged`` and
``eigenvector(., root, mode)``, plus the crossings on a ``crossing`` dimension.

Several sweeps (Mach numbers, densities, configurations, methods) are stacked into
``DIR/flutter.nc`` with the contract's layout for every method: ``damping``, ``frequency``, ``k``,
``eigenvalue``, ``converged`` on (case, velocity, root) and ``eigenvector`` on (case, velocity,
root, mode), where ``velocity`` is the point index of each case's sweep. A p-k point is one flight
velocity for all roots; a k-method point is one k value, each root at its own V = omega b / k, so
``root_velocity(case, velocity, root)`` holds the airspeed of each root for every method (the
flight velocity for p-k) and ``velocity_value(case, velocity)`` the flight velocity (NaN for the
k method); ``method(case)`` says which. Their crossings are listed in ``DIR/summary.json`` (a list
of ``{"mach", "density", "velocity", "frequency", "root", "kind", ..., "units"}``), the tables in
Nastran's FLUTTER SUMMARY layout in ``DIR/flutter_summary.txt`` and the V-g / V-f figures in
``DIR/vg_<case>.png``.

Units: the numbers are in the model's consistent units; :func:`label_units` labels velocity and
density with the case's unit system (structures.units) in the attrs, and every summary.json entry
carries them under ``units``.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import xarray as xr

from flutter.crossings import Crossing
from structures.common.files import write_dataset, write_json, write_text
from structures.units import unit_labels

#: Crossing kinds that are flutter points (a root's damping crossing zero at a non-zero
#: frequency): classical and body-freedom flutter (flutter.summary.crossing_kinds).
FLUTTER_KINDS = ("flutter", "body_freedom_flutter")
KINDS = FLUTTER_KINDS + ("divergence",)


def is_flutter(kind: str) -> bool:
    """True for a flutter crossing of any kind (:data:`FLUTTER_KINDS`), False for divergence."""
    return str(kind) in FLUTTER_KINDS


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
               modes: tuple, sweep: str = "velocity", method: str = "PK", k: np.ndarray | None = None,
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
    velocity : ndarray, shape (npts,), or (npts, nroot) for a k sweep (V = omega b / k per root)
    density, mach : ndarray, shape (npts,)
    b : float
        Reference semichord (REFC / 2) for k = omega b / V.
    modes : tuple of int
        Mode ids.
    sweep : {"velocity", "density", "k"}
        Name of the sweep dimension (``"k"``: the k method, ``velocity`` a data variable).
    k : ndarray, shape (npts,), optional
        Reduced frequencies of a k sweep (required for ``sweep="k"``).

    Returns
    -------
    xarray.Dataset
        dims (sweep, root, mode); velocity and density labelled "model units" (see
        :func:`label_units`).
    """
    omega = np.abs(p.imag)
    dim = sweep
    velocity = np.asarray(velocity, dtype=float)
    data = {
        "damping": ((dim, "root"), damping, {"units": "1", "long_name": "damping g = 2 gamma"}),
        "frequency": ((dim, "root"), omega / (2 * np.pi), {"units": "Hz"}),
        "eigenvalue": ((dim, "root"), p, {"units": "rad/s", "long_name": "p = omega (gamma + i)"}),
        "eigenvector": ((dim, "root", "mode"), normalise_eigenvectors(u),
                        {"units": "1", "long_name": "modal coordinates, largest = 1"}),
        "converged": ((dim, "root"), np.asarray(converged, dtype=bool)),
    }
    k_attrs = {"units": "1", "long_name": "reduced frequency k = omega b / V, b = refc/2"}
    if sweep == "k":
        data["velocity"] = ((dim, "root"), velocity,
                            {"long_name": "V = omega b / k of each root (k method)"})
        coords = {dim: (dim, np.asarray(k, dtype=float), k_attrs)}
        along = {"density": density, "mach": mach}
    else:
        data["k"] = ((dim, "root"), omega * b / velocity[:, None], k_attrs)
        coords = {dim: np.asarray(velocity if sweep == "velocity" else density, dtype=float)}
        along = {"density": density, "mach": mach} if sweep == "velocity" else \
            {"velocity": velocity, "mach": mach}
    ds = xr.Dataset(
        data,
        coords={**coords, "root": np.arange(1, p.shape[1] + 1), "mode": np.asarray(modes, dtype=int)},
        attrs={"method": method, "refc": 2.0 * b, "sweep": sweep,
               "conventions": "p = omega (gamma + i), g = 2 gamma, k = omega b / V, b = refc/2; "
                              "real roots: g = p refc / (V ln 2) (Nastran)",
               **(attrs or {})},
    )
    ds = ds.assign_coords({name: (dim, np.asarray(v, dtype=float)) for name, v in along.items()})
    return label_units(ds, None)


def label_units(ds: xr.Dataset, system: str | None) -> xr.Dataset:
    """A copy of a sweep or flutter.nc Dataset with the unit labels of ``system`` on its flight
    quantities (velocity, density and their per-root / crossing / per-case variants) and in attrs
    ``unit_system``; ``None`` labels them "model units" (a bare deck). The numbers are unchanged.

    Parameters
    ----------
    ds : xarray.Dataset
    system : {"si", "english_in", "english_ft"} or None
    """
    labels = unit_labels(system)
    ds = ds.copy()
    for quantity in ("velocity", "density"):
        for name in (quantity, f"{quantity}_value", f"root_{quantity}", f"crossing_{quantity}",
                     f"case_{quantity}"):
            if name in ds.variables:
                ds[name].attrs["units"] = getattr(labels, quantity)
    ds.attrs["unit_system"] = labels.system
    return ds


def units_entry(system: str | None) -> dict:
    """The ``units`` of a summary.json crossing: system name and velocity / density / frequency."""
    labels = unit_labels(system)
    return {"system": labels.system, "velocity": labels.velocity, "density": labels.density,
            "frequency": labels.frequency}


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
    """The crossings stored in a sweep Dataset as summary.json entries.

    Each entry: ``mach``, ``density``, ``velocity``, ``frequency`` [Hz], ``root``, ``kind``
    (``flutter``, ``body_freedom_flutter`` or ``divergence``: :data:`KINDS`), ``converged``,
    ``method``, ``root_label`` (when the sweep names its root, e.g. "short period":
    :func:`flutter.rigid_roots.label_rigid_roots`) and ``units`` (:func:`units_entry` of the
    Dataset's ``unit_system`` attribute, set by :func:`label_units`; "model units" when absent);
    matched points
    (:func:`flutter.matched.label_crossings`) add ``altitude`` [m], ``ktas`` and ``keas`` [kn],
    their units in ``units`` too.
    """
    if "crossing_root" not in ds:
        return []
    units = units_entry(ds.attrs.get("unit_system"))
    flight = [name for name in ("altitude", "ktas", "keas") if f"crossing_{name}" in ds]
    units.update({name: ds[f"crossing_{name}"].attrs["units"] for name in flight})
    labels = (dict(zip(ds["root"].values.tolist(), ds["root_label"].values.astype(str)))
              if "root_label" in ds.coords else {})
    out = []
    for i in range(ds.sizes.get("crossing", 0)):
        root_label = labels.get(int(ds.crossing_root[i]), "")
        out.append({"mach": float(ds.crossing_mach[i]), "density": float(ds.crossing_density[i]),
                    "velocity": float(ds.crossing_velocity[i]),
                    "frequency": float(ds.crossing_frequency[i]),
                    "root": int(ds.crossing_root[i]), "kind": str(ds.crossing_kind.values[i]),
                    "converged": bool(ds.crossing_converged[i]),
                    "method": str(ds.attrs.get("method", "")), "units": dict(units),
                    **({"root_label": root_label} if root_label else {}),
                    **{name: float(ds[f"crossing_{name}"][i]) for name in flight}})
    return out


def _per_root(s: xr.Dataset, name: str) -> np.ndarray:
    """Values of a sweep quantity on (point, root[, mode]), broadcasting a per-point one over roots
    (the flight velocity of a p-k sweep, the k of a k-method sweep)."""
    dim, v = s.attrs["sweep"], s[name]
    if "root" not in v.dims:
        return np.repeat(v.values[:, None], s.sizes["root"], axis=1)
    return v.transpose(dim, "root", ...).values


def summary_entries(sweeps: list[xr.Dataset], labels: list[dict]) -> list[dict]:
    """The summary.json list: :func:`crossings_of` every sweep, with ``case`` (index in flutter.nc)
    and the case's ``configuration``."""
    summary = []
    for c, (s, lab) in enumerate(zip(sweeps, labels)):
        for entry in crossings_of(s):
            entry["case"] = c
            if lab.get("configuration") is not None:
                entry["configuration"] = str(lab["configuration"])
            summary.append(entry)
    return summary


def stack_cases(sweeps: list[xr.Dataset], labels: list[dict]) -> xr.Dataset:
    """Stack sweeps into the flutter.nc layout (case, velocity, root) and (case, velocity, root, mode).

    Parameters
    ----------
    sweeps : list of xarray.Dataset
        Results of :func:`flutter.pk.pk_solve` (velocity or density sweeps) or
        :func:`flutter.kmethod.k_solve` (k sweeps); same roots and modes.
    labels : list of dict
        Per case: ``mach``, ``density`` (or ``altitude``), ``configuration``.

    Returns
    -------
    xarray.Dataset
        ``damping``, ``frequency``, ``k``, ``eigenvalue``, ``converged`` on (case, velocity, root)
        and ``eigenvector`` on (case, velocity, root, mode) for every method (DESIGN.md section 6).
        ``velocity`` is the point index of each case's sweep (NaN / False padded when sweeps differ
        in length). ``root_velocity`` (case, velocity, root) is the airspeed of each root: the
        flight velocity for p-k, V = omega b / k for the k method, whose points are its k values
        (one k for all roots of a point, each root at its own V). ``velocity_value``,
        ``density_value``, ``mach_value`` (case, velocity) hold the flight point (``velocity_value``
        NaN for the k method); ``method`` (case) names the method of each case; coordinate
        ``root_label(root)`` ("short period", "plunge", ...: :func:`flutter.rigid_roots.root_labels`)
        when the sweeps carry it.
    """
    npts = max(s.sizes[s.attrs["sweep"]] for s in sweeps)
    nc = len(sweeps)
    nroot, nmode = sweeps[0].sizes["root"], sweeps[0].sizes["mode"]

    def padded(values, shape, dtype, fill):
        out = np.full((nc, npts) + shape, fill, dtype=dtype)
        for c, vals in enumerate(values):
            out[c, :vals.shape[0]] = vals
        return out

    def attrs_of(name):
        return next(s[name].attrs for s in sweeps if name in s.variables)

    dims3 = ("case", "velocity", "root")
    ds = xr.Dataset(
        {name: (dims3, padded([_per_root(s, name) for s in sweeps], (nroot,), dt, fill),
                attrs_of(name))
         for name, dt, fill in (("damping", float, np.nan), ("frequency", float, np.nan),
                                ("k", float, np.nan), ("eigenvalue", complex, np.nan),
                                ("converged", bool, False))},
        coords={"case": np.arange(nc), "velocity": np.arange(npts),
                "root": sweeps[0]["root"].values, "mode": sweeps[0]["mode"].values},
        attrs={"layout": "velocity is the point index of each case's sweep; flight point in "
                         "velocity_value / density_value / mach_value; airspeed of each root in "
                         "root_velocity (k method: V = omega b / k per root at each k point)",
               "conventions": sweeps[0].attrs.get("conventions", "")},
    )
    ds["eigenvector"] = (dims3 + ("mode",),
                         padded([_per_root(s, "eigenvector") for s in sweeps], (nroot, nmode),
                                complex, np.nan), sweeps[0]["eigenvector"].attrs)
    ds["root_velocity"] = (dims3, padded([_per_root(s, "velocity") for s in sweeps], (nroot,),
                                         float, np.nan),
                           {"long_name": "airspeed of each root (k method: omega b / k)"})
    for name in ("velocity", "density", "mach"):
        vals = [s[name].values if s[name].dims == (s.attrs["sweep"],)
                else np.full(s.sizes[s.attrs["sweep"]], np.nan) for s in sweeps]
        ds[f"{name}_value"] = (("case", "velocity"), padded(vals, (), float, np.nan), attrs_of(name))
    ds["method"] = ("case", np.array([s.attrs.get("method", "") for s in sweeps], dtype=str))
    for key in ("mach", "density", "altitude", "configuration"):
        vals = [lab.get(key) for lab in labels]
        if any(v is not None for v in vals):
            if key == "configuration":
                arr = np.array(["" if v is None else str(v) for v in vals], dtype=str)
            else:
                arr = np.array([np.nan if v is None else float(v) for v in vals], dtype=float)
            ds = ds.assign_coords({f"case_{key}": ("case", arr)})
    if any("root_label" in s.coords for s in sweeps):
        ds = ds.assign_coords(root_label=("root", _root_labels(sweeps), {
            "long_name": "flight-mechanics name of rigid-body roots ('' elastic; cases that "
                         "disagree joined by ' / ')"}))
    systems = {s.attrs.get("unit_system") for s in sweeps}
    return label_units(ds, systems.pop() if len(systems) == 1 else None)


def _root_labels(sweeps: list[xr.Dataset]) -> np.ndarray:
    """(nroot,) str: each root's ``root_label`` over the cases (distinct ones joined by ' / ')."""
    per_case = [s["root_label"].values.astype(str) for s in sweeps if "root_label" in s.coords]
    out = []
    for r in range(sweeps[0].sizes["root"]):
        names = list(dict.fromkeys(str(lab[r]) for lab in per_case if lab[r]))
        out.append(" / ".join(names))
    return np.array(out, dtype=str)


def write_flutter(out_dir: str | os.PathLike, sweeps: list[xr.Dataset], labels: list[dict], *,
                  units: str | None = None, title: str = "") -> Path:
    """Write the flutter outputs of one run into ``out_dir`` (DESIGN.md section 6).

    - ``flutter.nc``: :func:`stack_cases` of every sweep (p-k, PKNL and k method alike);
    - ``summary.json``: the list of crossings (:func:`crossings_of`, with ``case``,
      ``configuration`` and ``units``);
    - ``flutter_summary.txt``: Nastran's FLUTTER SUMMARY layout, one table per case and root
      (:func:`flutter.nastran_text.flutter_summary_text`), to compare line by line with an F06;
    - ``vg_<case>.png``: the V-g / V-f figure of each case (:func:`flutter.plots.plot_vg`).

    Parameters
    ----------
    out_dir : path
    sweeps : list of xarray.Dataset
        Sweep results, one per case.
    labels : list of dict
        Per case: ``mach``, ``density``, ``configuration``.
    units : {"si", "english_in", "english_ft"} or None
        The case's unit system (None: "model units").
    title : str
        Heading of the text file and prefix of the figure titles (e.g. the deck name).

    Returns
    -------
    Path
        The output directory.
    """
    from flutter.nastran_text import flutter_summary_text
    from flutter.plots import plot_vg

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    sweeps = [label_units(s, units) for s in sweeps]
    write_dataset(stack_cases(sweeps, labels), out_dir / "flutter.nc")
    write_json(summary_entries(sweeps, labels), out_dir / "summary.json")
    write_text(flutter_summary_text(sweeps, title=title), out_dir / "flutter_summary.txt")
    for c, (s, lab) in enumerate(zip(sweeps, labels)):
        where = ", ".join(f"{name} {lab[key]:.4g}" for key, name in (("mach", "Mach"),
                                                                      ("density", "density"))
                          if lab.get(key) is not None)
        fig = plot_vg(s, title=f"{title} {lab.get('configuration', '')} {where}".strip())
        fig.savefig(out_dir / f"vg_{c + 1}.png", dpi=90)
    return out_dir
