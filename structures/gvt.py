"""Ground-vibration-test (GVT) modes as a first-class input: UFF 15/55 and netCDF.

The GVT Dataset follows the modes layout of DESIGN.md section 6:

- dims ``mode`` (the test's own mode numbers, e.g. 7, 8, 9, 11, ...) and ``dof``;
- ``frequency(mode)`` [Hz], ``damping(mode)`` (modal viscous damping ratio zeta, fraction of
  critical; g = 2*zeta), ``shape(mode, dof)`` (real, any scaling), optional ``name(mode)``
  (e.g. ``"SW1B"``) and ``modal_mass(mode)`` as the file gives it;
- coordinates ``grid(dof)`` (the model's grid ids) and ``component(dof)`` (1..6, translations and
  rotations in the model's BASIC frame), plus ``x(dof)``, ``y(dof)``, ``z(dof)`` when the file
  carries node coordinates (UFF 15 or 2411);
- attrs ``source`` (file name), ``reader`` (``pyuff`` / ``tolerant`` / ``netcdf`` / ``arrays``),
  ``units``.

A measured DOF is a (grid, component) pair. A UFF 55 record always carries 3 (or 6) values per node
even when a single-axis sensor measured one of them; by UFF convention (note 15 of the dataset
description) unused values are written as 0. :func:`read_uff` therefore drops, by default, every
(grid, component) that is exactly zero in every mode, so that SEREP never fits to zeros that were
never measured.

Reading uses pyuff first. Vendor files that pyuff's fixed-width parser rejects (Fortran ``D``
exponents, free-format columns, trailing blanks, CRLF) are read by a tolerant token-stream parser
of the same record layout (both in :mod:`structures.uff_records`); ``attrs["reader"]`` says which
one was used. UFF 55 stores values as E13.5, so a UFF round trip keeps 5-6 significant digits;
the netCDF form is exact.

Both readers refuse a damaged file with an :class:`InputError` naming the file, the dataset (its
position and line) and the mode: a dataset without its closing ``-1`` (a file cut short), a node
record with fewer values than the dataset's header says, text or NaN / inf where a number belongs,
and dataset numbers this reader does not know (e.g. a 58 where a 55 belongs). A node absent from one
mode but present in others is 0 there (UFF note 9), with a warning naming the mode and the nodes.
Every GVT Dataset, read or built from arrays, is checked by :func:`validate_gvt`, which also refuses
one mode recorded twice under two numbers (the same frequency and collinear shapes).

Test frequencies alone (a published GVT's table) are read from CSV by :func:`read_frequency_table`
into the same layout without ``shape`` and ``dof``; only the diagnosis takes them
(``shapes=False``), every other reader refuses them naming what it needs.

Measured mass properties (weight, CG, inertias) are not part of a UFF file: they come from the case
file.
"""
from __future__ import annotations

import os
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pyuff
import xarray as xr

from structures.common.errors import InputError
from structures.common.files import read_dataset, write_dataset
from structures.uff_records import from_pyuff, parse_tolerant, realise, split_blocks

_UFF_SUFFIXES = (".unv", ".uff", ".uf")
#: Two modes whose frequencies agree to ``REPEAT_RTOL`` (a UFF E13.5 record keeps 5-6 significant
#: digits) and whose shapes are collinear to ``REPEAT_MAC`` are one record given twice: two distinct
#: modes, even a symmetric and an antisymmetric one seen alike by one-sided sensors, differ in
#: frequency by more, and measurement noise keeps two records of different modes below that MAC.
REPEAT_RTOL, REPEAT_MAC = 1e-6, 0.9999


def make_gvt_dataset(frequency, shape, grid, component, *, mode=None, damping=None, name=None,
                     modal_mass=None, xyz=None, source: str = "", reader: str = "arrays",
                     units: str = "") -> xr.Dataset:
    """Build and validate a GVT Dataset from arrays.

    Parameters
    ----------
    frequency : array_like, shape (n_mode,)
        Measured natural frequencies [Hz].
    shape : array_like, shape (n_mode, n_dof), or None
        Measured mode shapes (real, any scaling); None for frequencies alone (a published
        frequency table: no ``shape``, no ``dof`` dim, ``grid`` and ``component`` None too).
    grid, component : array_like of int, shape (n_dof,), or None
        The model grid id and component (1..6, basic frame) of every measured DOF.
    mode : array_like of int, shape (n_mode,), optional
        Test mode numbers; default 1..n_mode.
    damping : array_like, shape (n_mode,), optional
        Modal viscous damping ratio zeta; default 0.
    name : sequence of str, shape (n_mode,), optional
        Mode names such as ``"SW1B"``.
    modal_mass : array_like, shape (n_mode,), optional
        Modal mass as the test report gives it (informative only).
    xyz : array_like, shape (n_dof, 3), optional
        Basic position of each DOF's grid.
    source, reader, units : str
        Provenance attributes.

    Returns
    -------
    xarray.Dataset
        The validated GVT Dataset, DOFs sorted by (grid, component), modes by mode number.
    """
    if shape is None and any(a is not None for a in (grid, component, xyz)):
        raise InputError(f"GVT data from {source or 'arrays'}: measured DOFs (grid, component or "
                         "xyz) without mode shapes. Fix: give shape (n_mode, n_dof) with them, or "
                         "None for all four (frequencies alone).")
    frequency = np.asarray(frequency, dtype=float)
    n_mode = frequency.shape[0] if frequency.ndim == 1 else -1
    mode = np.arange(1, n_mode + 1) if mode is None else np.asarray(mode)
    data_vars = {
        "frequency": (("mode",), frequency, {"units": "Hz"}),
        "damping": (("mode",), np.zeros(n_mode) if damping is None else np.asarray(damping, float),
                    {"units": "1", "long_name": "modal viscous damping ratio zeta (g = 2*zeta)"}),
    }
    if shape is not None:
        data_vars["shape"] = (("mode", "dof"), np.asarray(shape, dtype=float),
                              {"units": units or "model units"})
    if name is not None:
        data_vars["name"] = (("mode",), np.asarray([str(s) for s in name], dtype=object))
    if modal_mass is not None:
        data_vars["modal_mass"] = (("mode",), np.asarray(modal_mass, dtype=float))
    coords = {"mode": mode}
    if shape is not None:
        coords.update({"grid": ("dof", np.asarray(grid)), "component": ("dof", np.asarray(component))})
    if xyz is not None:
        xyz = np.asarray(xyz, dtype=float)
        coords.update({"x": ("dof", xyz[:, 0]), "y": ("dof", xyz[:, 1]), "z": ("dof", xyz[:, 2])})
    try:
        ds = xr.Dataset(data_vars, coords=coords)
    except ValueError as exc:
        raise InputError(f"GVT data from {source or 'arrays'}: inconsistent array sizes ({exc}). Fix: "
                         "give frequency (n_mode,), shape (n_mode, n_dof), grid and component (n_dof,).")
    ds.attrs.update({"source": str(source), "reader": reader, "units": units,
                     "frame": "basic", "damping_convention": "zeta (fraction of critical); g = 2*zeta"})
    validate_gvt(ds, shapes=shape is not None)
    if shape is None:
        return ds.sortby("mode")
    return ds.sortby("mode").isel(dof=np.lexsort((ds["component"].values, ds["grid"].values)))


def validate_gvt(ds: xr.Dataset, *, shapes: bool = True) -> None:
    """Check a GVT Dataset and raise :class:`InputError` naming the offending mode or DOF.

    Checks: required variables and dims, integer grid ids and components 1..6, no duplicate
    mode numbers, no duplicate (grid, component), finite non-negative frequencies, finite shapes
    and damping, no mode with an all-zero shape, and no mode recorded twice under two numbers
    (:func:`repeated_records`).

    Parameters
    ----------
    ds : xarray.Dataset
    shapes : bool
        True: the mode shapes are required (correlation, tuning); a frequency table is refused
        naming what takes one. False: frequencies alone are accepted (``shape`` absent; the
        diagnosis), and shapes, when present, are checked as above.
    """
    where = f"GVT file {ds.attrs.get('source') or '(arrays)'}"
    if shapes and "shape" not in ds and "frequency" in ds:
        raise InputError(f"{where}: test frequencies without mode shapes: correlation and tuning "
                         "pair and fit the modes by their shapes (MAC, SEREP). Fix: give the GVT "
                         "with its shapes (UFF 55 or netCDF); `pipeline diagnose` takes "
                         "frequencies alone.")
    required = (("frequency", ("mode",)), ("damping", ("mode",)))
    if shapes or "shape" in ds:
        required += (("shape", ("mode", "dof")),)
    for var, dims in required:
        if var not in ds or ds[var].dims != dims:
            raise InputError(f"{where}: variable {var}{dims} is missing. Fix: build it with "
                             "make_gvt_dataset or read it with load_gvt.")
    for coord in ("mode", "grid", "component") if "shape" in ds else ("mode",):
        if coord not in ds.coords:
            raise InputError(f"{where}: coordinate {coord!r} is missing. Fix: name every DOF by "
                             "(grid, component).")
    modes = ds["mode"].values
    uniq, counts = np.unique(modes, return_counts=True)
    if np.any(counts > 1):
        raise InputError(f"{where}: duplicate mode numbers {uniq[counts > 1].tolist()}. Fix: give "
                         "every test mode its own number.")
    _validate_frequencies(ds, where)
    if "shape" in ds:
        _validate_shapes(ds, where)


def _validate_frequencies(ds: xr.Dataset, where: str) -> None:
    """Finite non-negative frequencies and finite damping (:func:`validate_gvt`)."""
    modes = ds["mode"].values
    freq = ds["frequency"].values
    if not np.all(np.isfinite(freq)) or np.any(freq < 0):
        bad_f = modes[~(np.isfinite(freq) & (freq >= 0))].tolist()
        raise InputError(f"{where}: frequencies of modes {bad_f} "
                         "are not finite and >= 0. Fix: correct the frequency records.")
    if not np.all(np.isfinite(ds["damping"].values)):
        raise InputError(f"{where}: damping of modes "
                         f"{modes[~np.isfinite(ds['damping'].values)].tolist()} is not finite.")


def _validate_shapes(ds: xr.Dataset, where: str) -> None:
    """The DOFs and shapes of :func:`validate_gvt`."""
    modes, freq = ds["mode"].values, ds["frequency"].values
    grid, comp = ds["grid"].values, ds["component"].values
    if not (np.issubdtype(grid.dtype, np.integer) and np.issubdtype(comp.dtype, np.integer)):
        raise InputError(f"{where}: grid and component must be integers. Fix: use the model's grid ids.")
    bad = (comp < 1) | (comp > 6)
    if np.any(bad):
        raise InputError(f"{where}: components {np.unique(comp[bad]).tolist()} are not in 1..6 "
                         f"(grids {np.unique(grid[bad]).tolist()}). Fix: use 1-3 translations, "
                         "4-6 rotations.")
    key = grid.astype(np.int64) * 10 + comp
    uk, kc = np.unique(key, return_counts=True)
    if np.any(kc > 1):
        dup = [(int(k // 10), int(k % 10)) for k in uk[kc > 1]]
        raise InputError(f"{where}: duplicate measured DOFs (grid, component) {dup}. Fix: keep one "
                         "value per DOF (average repeated roving-sensor measurements first).")
    shape = ds["shape"].values
    finite = np.isfinite(shape)
    if not np.all(finite):
        m_idx, d_idx = np.nonzero(~finite)
        bad_dofs = sorted({(int(modes[m]), int(grid[d]), int(comp[d])) for m, d in zip(m_idx, d_idx)})
        raise InputError(f"{where}: NaN/inf in the shape at (mode, grid, component) {bad_dofs[:10]}"
                         f"{' ...' if len(bad_dofs) > 10 else ''}. Fix: drop the DOF from every mode "
                         "(a DOF must be measured in all modes) or re-export the shapes.")
    zero = ~np.any(shape != 0.0, axis=1)
    if np.any(zero):
        raise InputError(f"{where}: modes {modes[zero].tolist()} have an all-zero shape. Fix: remove "
                         "them or re-export their shapes.")
    first, second = repeated_records(freq, shape)
    if first.size:
        pairs = [(int(modes[i]), int(modes[j])) for i, j in zip(first, second)]
        raise InputError(f"{where}: modes {pairs[:10]}{' ...' if len(pairs) > 10 else ''} are one "
                         f"record given twice (the same frequency to {REPEAT_RTOL:g} and collinear "
                         f"shapes, MAC >= {REPEAT_MAC}). Fix: keep one mode of each pair (average a "
                         "mode measured in two runs into one record).")


def repeated_records(frequency, shape) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of modes that are one record given twice: frequencies equal to ``REPEAT_RTOL`` and
    MAC(phi_i, phi_j) = (phi_i . phi_j)^2 / (|phi_i|^2 |phi_j|^2) >= ``REPEAT_MAC``.

    Parameters
    ----------
    frequency : (n_mode,) frequencies [Hz].
    shape : (n_mode, n_dof) real shapes, none all zero.

    Returns
    -------
    first, second : ndarray of int, shape (n_pair,)
        Positions along ``mode`` of each pair, first < second.
    """
    f = np.asarray(frequency, float)
    phi = np.asarray(shape, float)
    square = np.einsum("md,md->m", phi, phi)
    mac = (phi @ phi.T) ** 2 / np.outer(square, square)
    same_f = np.isclose(f[:, None], f[None, :], rtol=REPEAT_RTOL, atol=0.0)
    return np.nonzero(np.triu(same_f & (mac >= REPEAT_MAC), k=1))


def check_dofs_in_model(gvt: xr.Dataset, model_grids) -> None:
    """Raise :class:`InputError` naming every GVT node that is not a grid of the model.

    Parameters
    ----------
    gvt : xarray.Dataset
        GVT Dataset.
    model_grids : array_like of int, shape (n_grid,)
        The model's grid ids.
    """
    nodes = np.unique(gvt["grid"].values)
    missing = nodes[~np.isin(nodes, np.asarray(model_grids))]
    if missing.size:
        raise InputError(f"GVT file {gvt.attrs.get('source') or '(arrays)'}: nodes {missing.tolist()} "
                         "are not grids of the model. Fix: renumber the test nodes to the model's grid "
                         "ids (node numbers must be the model's GRID ids) or add those grids.")


# ---------------------------------------------------------------------------------------- UFF read
def read_uff(path: str | os.PathLike, *, drop_unmeasured: bool = True, units: str = "") -> xr.Dataset:
    """Read normal modes (UFF 55) and node positions (UFF 15 / 2411) into a GVT Dataset.

    Parameters
    ----------
    path : path-like
        Universal file (``.unv``/``.uff``).
    drop_unmeasured : bool
        Drop (grid, component) pairs that are exactly zero in every mode (UFF writes unused
        values as 0).
    units : str
        Unit label stored in attrs.

    Returns
    -------
    xarray.Dataset
        GVT Dataset; mode names come from ID line 4 of each UFF 55 record when it is not
        ``NONE``/blank.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"GVT file {path}: no such file. Fix: check the path.")
    blocks = split_blocks(path)
    n_modes = sum(1 for kind, _, _ in blocks if kind == 55)
    try:
        sets = pyuff.UFF(str(path)).read_sets()
        sets = [sets] if isinstance(sets, dict) else list(sets)
        nodes, records = from_pyuff(sets, path)
        reader = "pyuff"
    except InputError:
        raise
    except Exception:  # pyuff raises bare Exception on any deviation from the fixed-width layout
        records = []
    if len(records) != n_modes or not records:
        # pyuff failed or silently missed blocks (delimiters with trailing blanks, ...): tolerant reader
        nodes, records = parse_tolerant(path, blocks)
        reader = "tolerant"
    return _assemble(path, nodes, records, drop_unmeasured=drop_unmeasured, reader=reader, units=units)


def _assemble(path: Path, nodes: dict, records: list, *, drop_unmeasured: bool, reader: str,
              units: str) -> xr.Dataset:
    if not records:
        raise InputError(f"GVT file {path}: no dataset 55 (mode shapes) found. Fix: export the modes as "
                         "universal dataset 55.")
    ndvs = {r["ndv"] for r in records}
    if len(ndvs) > 1:
        raise InputError(f"GVT file {path}: modes mix 3 and 6 values per node. Fix: export all modes "
                         "with the same data characteristic.")
    ndv = ndvs.pop()
    bad_cs = sorted(nid for nid, (_, dcs, ucs) in nodes.items() if dcs != 0 or ucs != 0)
    if bad_cs:
        raise InputError(f"GVT file {path}: nodes {bad_cs[:20]} use a non-global definition or "
                         "displacement coordinate system. Fix: export nodes and shapes in the global "
                         "frame, which must be the model's basic frame.")
    all_nodes = np.unique(np.concatenate([r["nodes"] for r in records]))
    shape = np.zeros((len(records), all_nodes.size, ndv))
    freq, zeta = np.empty(len(records)), np.empty(len(records))
    for k, r in enumerate(records):
        u, cnt = np.unique(r["nodes"], return_counts=True)
        if np.any(cnt > 1):
            raise InputError(f"GVT file {path}, mode {r['mode']}: nodes {u[cnt > 1].tolist()} appear twice. "
                             "Fix: one record per node.")
        bad = ~np.all(np.isfinite(r["values"]), axis=1)
        if np.any(bad):
            raise InputError(f"GVT file {path}, mode {r['mode']}: NaN/inf in the shape at nodes "
                             f"{r['nodes'][bad][:10].tolist()}. Fix: correct those values or "
                             "re-export the shapes.")
        absent = np.setdiff1d(all_nodes, r["nodes"])
        if absent.size:
            warnings.warn(f"GVT file {path}, mode {r['mode']}: no values for nodes "
                          f"{absent[:10].tolist()}{' ...' if absent.size > 10 else ''} "
                          f"({r['nodes'].size} of {all_nodes.size} nodes); taken as 0 (UFF note 9). "
                          "Fix: re-export the mode if the file was cut.", stacklevel=3)
        freq[k], zeta[k], vals = realise(r)
        # nodes absent from a record are 0 (UFF note 9)
        shape[k, np.searchsorted(all_nodes, r["nodes"])] = vals
    grid = np.repeat(all_nodes, ndv)
    comp = np.tile(np.arange(1, ndv + 1), all_nodes.size)
    shape = shape.reshape(len(records), -1)
    keep = np.any(shape != 0.0, axis=0) if drop_unmeasured else np.ones(grid.size, bool)
    xyz = None
    if nodes:
        missing = [int(g) for g in all_nodes if int(g) not in nodes]
        if missing:
            raise InputError(f"GVT file {path}: nodes {missing[:20]} have shapes but no coordinates in the "
                             "dataset 15/2411. Fix: export all measured nodes.")
        xyz = np.array([nodes[int(g)][0] for g in grid[keep]]).reshape(-1, 3)
    names = [r["name"] for r in records]
    has_names = any(s and s.upper() != "NONE" for s in names)
    return make_gvt_dataset(freq, shape[:, keep], grid[keep], comp[keep],
                            mode=[r["mode"] for r in records], damping=zeta,
                            name=[("" if s.upper() == "NONE" else s) for s in names] if has_names else None,
                            modal_mass=[r["modal_mass"] for r in records], xyz=xyz, source=str(path),
                            reader=reader, units=units)


# --------------------------------------------------------------------------------------- UFF write
def write_uff(ds: xr.Dataset, path: str | os.PathLike, *, title: str = "GVT modes") -> Path:
    """Write a GVT Dataset as UFF 15 (when it has coordinates) + one UFF 55 per mode, with pyuff.

    Nodes get 3 values (6 when any rotation is present); DOFs not in the Dataset are written as 0
    (UFF note 15), which :func:`read_uff` drops again. The mode name goes to ID line 4. Written
    atomically (temp file + rename).
    """
    validate_gvt(ds)
    path = Path(path)
    grid, comp = ds["grid"].values, ds["component"].values
    nodes = np.unique(grid)
    ndv = 6 if np.any(comp > 3) else 3
    full = np.zeros((ds.sizes["mode"], nodes.size, ndv))
    full[:, np.searchsorted(nodes, grid), comp - 1] = ds["shape"].values
    sets = []
    if "x" in ds.coords:
        first = np.unique(grid, return_index=True)[1]
        xyz = {c: ds[c].values[first].astype(float) for c in ("x", "y", "z")}
        sets.append(pyuff.prepare_15(node_nums=nodes.astype(int), **xyz))
        sets[-1].update(def_cs=np.zeros(nodes.size, int), disp_cs=np.zeros(nodes.size, int),
                        color=np.zeros(nodes.size, int))
    names = ds["name"].values if "name" in ds else [""] * ds.sizes["mode"]
    mmass = ds["modal_mass"].values if "modal_mass" in ds else np.zeros(ds.sizes["mode"])
    for k, mode in enumerate(ds["mode"].values):
        rec = dict(type=55, id1=title, id2=f"GVT mode {int(mode)}", id3="NONE", id4=str(names[k]) or "NONE",
                   id5=f"Mode {int(mode)} Frequency {float(ds['frequency'].values[k]):.5e}",
                   model_type=1, analysis_type=2, data_ch=3 if ndv == 6 else 2, spec_data_type=8,
                   data_type=2, n_data_per_node=ndv, load_case=1, mode_n=int(mode),
                   freq=float(ds["frequency"].values[k]), modal_m=float(mmass[k]),
                   modal_damp_vis=float(ds["damping"].values[k]), modal_damp_his=0.0,
                   node_nums=nodes.astype(int))
        rec.update({f"r{j + 1}": full[k, :, j] for j in range(ndv)})
        sets.append(rec)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    os.remove(tmp)
    try:
        pyuff.UFF(tmp).write_sets(sets, mode="overwrite")
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    return path


# ------------------------------------------------------------------------------------------ netCDF
def write_gvt(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Write a GVT Dataset, with shapes or frequencies alone, to netCDF4 atomically (the exact
    form of the same Dataset)."""
    validate_gvt(ds, shapes=False)
    return write_dataset(ds, path)


def read_gvt(path: str | os.PathLike, *, shapes: bool = True) -> xr.Dataset:
    """Read a GVT Dataset written by :func:`write_gvt` and validate it (``shapes`` as
    :func:`validate_gvt`)."""
    ds = read_dataset(path)
    if "name" in ds:
        ds["name"] = ds["name"].astype(object)
    ds.attrs["source"] = str(path)
    validate_gvt(ds, shapes=shapes)
    return ds


#: Columns of a frequency table (:func:`read_frequency_table`); the first two are required.
TABLE_COLUMNS = ("mode", "frequency", "damping", "name")


def read_frequency_table(path: str | os.PathLike, *, shapes: bool = False) -> xr.Dataset:
    """Read test frequencies without shapes, as a published GVT gives them, from a CSV table.

    The first line that is neither blank nor a ``#`` comment names the columns, separated by
    commas: ``mode`` (the test's mode number) and ``frequency`` [Hz] are required, ``damping``
    (viscous damping ratio zeta, fraction of critical; blank or absent: 0) and ``name`` (e.g.
    ``SW1B``) optional, in any order::

        # X-56A GVT, published table
        mode, frequency, damping, name
        7, 5.42, 0.012, SW1B

    Parameters
    ----------
    path : path-like
    shapes : bool
        True refuses the table (:func:`validate_gvt`: a step that needs mode shapes).

    Returns
    -------
    xarray.Dataset
        The GVT layout without ``shape`` and ``dof`` (:func:`make_gvt_dataset` with
        ``shape=None``), modes sorted by number; attrs ``reader`` ``"table"``.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"GVT file {path}: no such file. Fix: check the path.")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"GVT file {path}: not a text table ({exc.reason} at byte {exc.start}). "
                         "Fix: save the table as CSV text.") from None
    rows = [(n, [f.strip() for f in line.split(",")]) for n, line in
            enumerate(text.splitlines(), start=1) if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        raise InputError(f"GVT file {path}: no header line. Fix: start the table with the "
                         "columns, e.g. 'mode, frequency, damping, name'.")
    line, header = rows[0]
    columns = [h.lower() for h in header]
    unknown = [h for h in columns if h not in TABLE_COLUMNS]
    if unknown or len(set(columns)) != len(columns) or not {"mode", "frequency"} <= set(columns):
        raise InputError(f"GVT file {path}, line {line}: columns {header} must name 'mode' and "
                         f"'frequency' [Hz] once each, and otherwise only {list(TABLE_COLUMNS[2:])}"
                         f"{f' (unknown: {unknown})' if unknown else ''}. Fix: rename the header.")
    if len(rows) == 1:
        raise InputError(f"GVT file {path}: the table lists no mode. Fix: one line per test mode "
                         "below the header.")
    values = {c: [] for c in columns}
    for line, fields in rows[1:]:
        if len(fields) != len(columns):
            raise InputError(f"GVT file {path}, line {line}: {len(fields)} fields for the "
                             f"{len(columns)} columns {columns}. Fix: one value per column (a "
                             "blank damping is 0).")
        for column, field_ in zip(columns, fields):
            values[column].append(_table_value(column, field_, f"GVT file {path}, line {line}"))
    ds = make_gvt_dataset(values["frequency"], None, None, None, mode=values["mode"],
                          damping=values.get("damping"), name=values.get("name"),
                          source=str(path), reader="table")
    if shapes:
        validate_gvt(ds)             # refuses it, naming the diagnosis that takes it
    return ds


def _table_value(column: str, text: str, where: str):
    """One field of a frequency table: the mode an integer, frequency and damping numbers
    (a blank damping 0), the name as written."""
    if column == "name":
        return text
    if column == "damping" and not text:
        return 0.0
    try:
        number = float(text)
    except ValueError:
        raise InputError(f"{where}: {column} {text!r} is not a number. Fix: correct the "
                         "field.") from None
    if column == "mode" and not (np.isfinite(number) and number == round(number)
                                 and 1 <= number < 2 ** 31):
        raise InputError(f"{where}: mode {text!r} is not a mode number (an integer, 1 or more, as "
                         "a UFF label). Fix: number the test modes 1, 2, ... or as the test "
                         "report does.")
    return int(number) if column == "mode" else number


def load_gvt(path: str | os.PathLike, *, shapes: bool = True, **kwargs) -> xr.Dataset:
    """Read a GVT file by suffix: ``.unv``/``.uff``/``.uf`` with :func:`read_uff`, ``.nc`` with
    :func:`read_gvt`, ``.csv`` (frequencies alone) with :func:`read_frequency_table`.

    ``shapes`` True (correlation, tuning) refuses a file without mode shapes, naming what
    accepts one; False (the diagnosis) takes frequencies alone. ``kwargs`` go to
    :func:`read_uff`."""
    suffix = Path(path).suffix.lower()
    if suffix in _UFF_SUFFIXES:
        return read_uff(path, **kwargs)
    if suffix == ".nc":
        return read_gvt(path, shapes=shapes)
    if suffix == ".csv":
        return read_frequency_table(path, shapes=shapes)
    raise InputError(f"GVT file {path}: unknown suffix {suffix!r}. Fix: use one of "
                     f"{list(_UFF_SUFFIXES) + ['.nc', '.csv']}.")
