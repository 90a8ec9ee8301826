"""Import modes computed elsewhere: Nastran (or MYSTRAN) SOL 103/145 OP2 files and F06 tables.

A user with existing Nastran results can skip our FE solver: :func:`modes_from_op2` turns the OP2
eigenvectors into the same modes Dataset :func:`structures.modal.compute_modes` returns (shapes
rotated from each grid's output frame to basic using the deck), and :func:`read_f06_eigenvalues`
reads the REAL EIGENVALUES tables of an F06.
"""
from __future__ import annotations

import io
import logging
import re
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
import xarray as xr

from structures.common.errors import InputError
from structures.modes import modes_dataset

_F06_TABLE = "R E A L   E I G E N V A L U E S"
_ROW = re.compile(r"^\s+(\d+)\s+(\d+)\s+([-+0-9.E]+)\s+([-+0-9.E]+)\s+([-+0-9.E]+)\s+([-+0-9.E]+)"
                  r"\s+([-+0-9.E]+)\s*$")


def read_f06_eigenvalues(path, table: int = 0) -> xr.Dataset:
    """Read one REAL EIGENVALUES table of an F06.

    Parameters
    ----------
    path : str or Path
    table : int
        Which table (0 = first, e.g. "before augmentation of residual vectors"; -1 = last).

    Returns
    -------
    xarray.Dataset with ``eigenvalue``, ``radians``, ``frequency`` [Hz], ``generalized_mass``,
    ``generalized_stiffness`` on dim ``mode``; attrs ``title`` (the table's sub-heading).
    """
    path = Path(path)
    if not path.exists():
        raise InputError(f"file {path}: no such F06. Fix: check the path.")
    lines = path.read_text(errors="replace").splitlines()
    starts = [i for i, line in enumerate(lines) if _F06_TABLE in line]
    if not starts:
        raise InputError(f"file {path}: no REAL EIGENVALUES table. Fix: give the F06 of a SOL 103 "
                         "or SOL 145 run.")
    try:
        start = starts[table]
    except IndexError:
        raise InputError(f"file {path}: table {table} requested but only {len(starts)} REAL "
                         "EIGENVALUES tables exist. Fix: choose 0..{len(starts) - 1}.") from None
    title = lines[start + 1].strip() if start + 1 < len(lines) else ""
    rows = []
    for line in lines[start + 2:]:
        match = _ROW.match(line)
        if match:
            rows.append([float(v) for v in match.groups()])
        elif rows and line.strip() and not line.lstrip().startswith(("MODE", "NO.", "NUMBER",
                                                                     "ORDER")):
            break
    values = np.array(rows)
    return xr.Dataset(
        {"eigenvalue": ("mode", values[:, 2], {"units": "(rad/s)^2"}),
         "radians": ("mode", values[:, 3], {"units": "rad/s"}),
         "frequency": ("mode", values[:, 4], {"units": "Hz"}),
         "generalized_mass": ("mode", values[:, 5]),
         "generalized_stiffness": ("mode", values[:, 6])},
        coords={"mode": values[:, 0].astype(int)},
        attrs={"source": "F06", "file": str(path), "title": title})


def modes_from_op2(op2_path, deck, *, subcase=None) -> xr.Dataset:
    """Modes Dataset from the eigenvectors of an OP2 file.

    Parameters
    ----------
    op2_path : str or Path
        OP2 with an eigenvector table (Nastran SOL 103/145 with ``DISP(PLOT)=ALL``; MYSTRAN too).
    deck : str, Path or FEModel
        The bulk data the OP2 came from: its grid positions and displacement frames rotate the
        shapes to the basic frame and its mass matrix gives the generalized masses.
    subcase : optional key of ``op2.eigenvectors``; default the first.

    Returns
    -------
    xarray.Dataset in the modes contract, ``attrs['source'] = 'OP2'``.
    """
    from pyNastran.op2.op2 import read_op2

    from structures.assembly import assemble_g, rotation_matrix
    from structures.bdf import read_model
    from structures.model import FEModel

    op2_path = Path(op2_path)
    if not op2_path.exists():
        raise InputError(f"file {op2_path}: no such OP2. Fix: check the path.")
    model = deck if isinstance(deck, FEModel) else read_model(deck)
    logging.getLogger("pynastran.quiet").setLevel(logging.CRITICAL)
    try:
        with redirect_stdout(io.StringIO()):
            op2 = read_op2(str(op2_path), build_dataframe=False, debug=None, mode="msc",
                           log=logging.getLogger("pynastran.quiet"))
    except Exception as exc:  # pyNastran raises many types for corrupt files
        raise InputError(f"file {op2_path}: pyNastran could not read the OP2 ({exc}). Fix: give an "
                         "OP2 written with PARAM,POST,-1/-2 (or MYSTRAN with DISP(PLOT)=ALL).") from exc
    if not op2.eigenvectors:
        raise InputError(f"file {op2_path}: the OP2 holds no eigenvectors. Fix: request "
                         "DISP(PLOT)=ALL in the case control of the SOL 103/145 run.")
    key = subcase if subcase is not None else next(iter(op2.eigenvectors))
    vec = op2.eigenvectors[key]
    node_ids = vec.node_gridtype[:, 0]
    rows = model.grids.index(node_ids, card="OP2 eigenvector", filename=str(op2_path))
    n_modes = vec.data.shape[0]
    shapes_cd = np.zeros((n_modes, 6 * len(model.grids)))
    for c in range(6):
        shapes_cd[:, 6 * rows + c] = vec.data[:, :, c]
    rot = rotation_matrix(model)
    shapes = (rot @ shapes_cd.T).T
    _, m_basic = assemble_g(model)
    gm = np.einsum("md,md->m", shapes, (m_basic @ shapes.T).T)
    lam = np.asarray(vec.eigns, float)
    freq = np.sqrt(np.abs(lam)) / (2.0 * np.pi)
    return modes_dataset(freq, shapes, model.grids.ids, model.grids.xyz, generalized_mass=gm,
                         source="OP2", deck=model.filename, units=model.units,
                         extra_attrs={"op2": str(op2_path),
                                      "generalized_mass_from": "deck mass matrix (PARAM COUPMASS "
                                                               "as in the deck)"})
