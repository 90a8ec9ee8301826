"""Universal File (UFF) records of a GVT export, parsed into node and mode records.

:func:`structures.gvt.read_uff` reads with pyuff first (:func:`from_pyuff` turns its dictionaries
into records) and falls back on :func:`parse_tolerant`, a token-stream parser of the same record
layout that reads what pyuff's fixed-width parser rejects (Fortran ``D`` exponents, free-format
columns, trailing blanks, CRLF). :func:`split_blocks` cuts the file into datasets and refuses a
dataset without its closing ``-1`` or with a number this reader does not know;
:func:`realise` turns a real or complex mode record into a frequency, a damping ratio and a real
shape. Records are dictionaries: ``mode``, ``name``, ``nodes`` (n_node,), ``values``
(n_node, ndv), ``ndv``, ``modal_mass``, ``freq`` or ``eig``, ``zeta``; nodes map a node id to
(xyz (3,), definition frame, displacement frame).
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from structures.common.errors import InputError

# A real number as Fortran writes it, possibly run together with its neighbour ("1.0E+00-2.0E+00")
# and possibly with a D exponent ("1.0D+00").
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eEdD][-+]?\d+)?|[-+]?(?i:nan|inf(?:inity)?)")
#: Datasets read: node coordinates (15, 2411) and mode shapes (55); datasets skipped: header (151),
#: units (164), trace lines and elements for display (82, 2412). Any other number is refused.
_READ_DATASETS = (15, 2411, 55)
_SKIPPED_DATASETS = (151, 164, 82, 2412)
#: UFF labels are I10 integers.
_LABEL_LIMIT = 2 ** 31


def from_pyuff(sets, path: Path) -> tuple[dict, list]:
    """Nodes {id: (xyz, def_cs, disp_cs)} and mode records from pyuff dictionaries."""
    nodes, records = {}, []
    where = f"GVT file {path}"
    for s in sets:
        kind = s.get("type")
        if kind in (15, 2411):
            n = len(s["node_nums"])
            def_cs = np.asarray(s.get("def_cs", np.zeros(n)))
            disp_cs = np.asarray(s.get("disp_cs", np.zeros(n)))
            for i, nid in enumerate(np.asarray(s["node_nums"])):
                nodes[_as_int(nid, where)] = (np.array([s["x"][i], s["y"][i], s["z"][i]], float),
                                              _as_int(def_cs[i], where), _as_int(disp_cs[i], where))
        elif kind == 55:
            ndv = int(s["n_data_per_node"])
            node_nums = np.asarray(s["node_nums"])
            vals = np.column_stack([np.asarray(s[f"r{j}"]) for j in range(1, ndv + 1)])
            if vals.shape[0] != node_nums.shape[0]:
                raise ValueError("pyuff returned inconsistent node and value counts")
            if int(s["analysis_type"]) == 2:
                eig = None
                freq, mmass = float(s["freq"]), float(s.get("modal_m", 0.0))
                zeta = float(s.get("modal_damp_vis", 0.0))
            elif int(s["analysis_type"]) in (3, 7):
                eig, freq, mmass, zeta = complex(s["eig"]), None, 0.0, None
            else:
                raise InputError(f"GVT file {path}, dataset 55 mode {s.get('mode_n')}: analysis type "
                                 f"{s['analysis_type']} is not normal (2) or complex (3) modes. Fix: export "
                                 "the test mode shapes.")
            records.append(dict(mode=int(s["mode_n"]), freq=freq, eig=eig, modal_mass=mmass, zeta=zeta,
                                name=str(s.get("id4", "")),
                                nodes=np.array([_as_int(v, where) for v in node_nums], np.int64),
                                values=vals, ndv=ndv))
    return nodes, records


def _as_int(value, where: str) -> int:
    """An integer label (node, mode, count, coordinate system) of a UFF record."""
    number = float(value)
    if not np.isfinite(number) or round(number) != number or abs(number) >= _LABEL_LIMIT:
        raise InputError(f"{where}: label {value} is not an integer label. Fix: node and mode "
                         "labels and counts must be integers (UFF I10).")
    return int(number)


def _numbers(lines: list[str], where: str, first_line: int) -> list[float]:
    """The numbers of numeric records; anything else on those lines raises naming the line."""
    out = []
    for n, line in enumerate(lines):
        found = _NUMBER.findall(line)
        junk = _NUMBER.sub(" ", line).replace(",", " ").strip()
        if junk:
            raise InputError(f"{where}, line {first_line + n}: {junk.split()[0]!r} is not a number "
                             f"({line.strip()!r}). Fix: correct or re-export the record.")
        out += [float(t.replace("D", "E").replace("d", "e")) for t in found]
    return out


def split_blocks(path: Path) -> list[tuple[int | None, list[str], int]]:
    """(dataset number, body lines, line number of the body's first line) of every dataset between
    ``-1`` delimiter lines; the number is None for a binary dataset header (``2414b``), which only
    pyuff reads. Raises for a dataset without its closing ``-1`` or with an unknown number."""
    raw = path.read_bytes()
    if not raw.strip():
        raise InputError(f"GVT file {path}: the file is empty. Fix: export the test modes as "
                         "universal datasets 15 and 55.")
    lines = [ln.rstrip() for ln in raw.decode("latin-1").splitlines()]
    blocks, i, n = [], 0, len(lines)
    while i < n:
        if lines[i].strip() != "-1":
            i += 1
            continue
        j = i + 1
        while j < n and lines[j].strip() != "-1":
            j += 1
        block = lines[i + 1:j]
        if j == n and any(ln.strip() for ln in block):
            raise InputError(f"GVT file {path}, dataset #{len(blocks) + 1} (line {i + 2}): no "
                             "closing -1 line: the file is cut short. Fix: re-export or copy the "
                             "whole file.")
        i = j + 1
        if not block or not block[0].split():
            continue
        head = block[0].split()[0]
        where = f"GVT file {path}, dataset #{len(blocks) + 1} (line {i - len(block)})"
        if re.fullmatch(r"\d+b", head):
            blocks.append((None, block[1:], i - len(block) + 1))
            continue
        if not head.isdigit():
            raise InputError(f"{where}: {head!r} is not a dataset number. Fix: each dataset starts "
                             "with its number on the line after -1.")
        kind = int(head)
        if kind not in _READ_DATASETS + _SKIPPED_DATASETS:
            raise InputError(f"{where}: dataset {kind} is not a dataset this reader knows; node "
                             "coordinates are 15 or 2411, mode shapes 55 (skipped: "
                             f"{', '.join(map(str, _SKIPPED_DATASETS))}). Fix: export the modes as "
                             "datasets 15 and 55, or remove the other datasets.")
        blocks.append((kind, block[1:], i - len(block) + 1))
    return blocks


def parse_tolerant(path: Path, blocks) -> tuple[dict, list]:
    """Token-stream parser of UFF 15/2411/55 tolerant of D exponents, CRLF, blanks, free format."""
    nodes, records = {}, []
    for number, (kind, body, line) in enumerate(blocks, start=1):
        where = f"GVT file {path}, dataset #{number} ({kind}, line {line - 1})"
        if kind is None:
            raise InputError(f"GVT file {path}: a binary dataset that pyuff could not read. Fix: export "
                             "ASCII universal files.")
        if kind in (15, 2411):
            vals = _numbers(body, where, line)
            if len(vals) % 7:
                raise InputError(f"{where}: {len(vals)} numbers, not 7 per node. "
                                 "Fix: check the node records.")
            for rec in np.reshape(vals, (-1, 7)):
                nodes[_as_int(rec[0], where)] = (rec[4:7].astype(float), _as_int(rec[1], where),
                                                 _as_int(rec[2], where))
        elif kind == 55:
            records.append(_parse_55(body, where, line))
    return nodes, records


def _parse_55(body: list[str], where: str, line: int) -> dict:
    """The record of one UFF 55 dataset (``body``: its lines after the dataset number, the
    first on line ``line``), real (analysis type 2) or complex (3, 7) modes."""
    if len(body) < 6:
        raise InputError(f"{where}: the dataset 55 is truncated. Fix: re-export the file.")
    name = body[3].strip()
    tok = _numbers(body[5:], where, line + 5)
    if (len(tok) < 8 or len(tok) < 8 + _as_int(tok[6], where) + _as_int(tok[7], where)
            or _as_int(tok[7], where) < 2):
        raise InputError(f"{where}: the header records 6-8 of the dataset 55 ({name!r}) are "
                         "incomplete. Fix: re-export the file.")
    _model, analysis, data_ch, _spec, data_type, ndv = (_as_int(t, where) for t in tok[:6])
    nint, nreal = _as_int(tok[6], where), _as_int(tok[7], where)
    ints = [_as_int(t, where) for t in tok[8:8 + nint]]
    reals = tok[8 + nint:8 + nint + nreal]
    rest = np.asarray(tok[8 + nint + nreal:])
    mode = ints[1] if len(ints) > 1 else None
    where = f"{where}, mode {mode}"
    if analysis not in (2, 3, 7) or mode is None:
        raise InputError(f"{where}: analysis type {analysis} is not normal (2) or complex (3) modes. "
                         "Fix: export the test mode shapes.")
    if data_ch not in (2, 3) or ndv not in (3, 6):
        raise InputError(f"{where}: data characteristic {data_ch} with {ndv} values per node is not a "
                         "3 or 6 DOF vector. Fix: export displacement vectors (data characteristic 2 or 3).")
    width = ndv * (2 if data_type == 5 else 1)
    if rest.size % (width + 1):
        raise InputError(f"{where}: {rest.size} numbers do not make whole node records of 1 node "
                         f"label + {width} values (the header's data type {data_type}, {ndv} values "
                         "per node): a node record is cut or has a value too many. Fix: correct the "
                         "node/value records or re-export the file.")
    rec = rest.reshape(-1, width + 1)
    values = rec[:, 1:] if data_type != 5 else rec[:, 1::2] + 1j * rec[:, 2::2]
    out = dict(mode=mode, name=name, nodes=np.array([_as_int(v, where) for v in rec[:, 0]], np.int64),
               values=values, ndv=ndv, modal_mass=0.0, freq=None, eig=None, zeta=None)
    if analysis == 2:
        out.update(freq=reals[0], modal_mass=reals[1] if nreal > 1 else 0.0,
                   zeta=reals[2] if nreal > 2 else 0.0)
    else:
        out.update(eig=complex(reals[0], reals[1]))
    return out


def realise(record: dict) -> tuple[float, float, np.ndarray]:
    """Frequency [Hz], zeta and a real shape from a real or complex UFF 55 record.

    Complex modes (analysis type 3): lambda = sigma + i*omega_d, f = |lambda|/(2*pi),
    zeta = -sigma/|lambda|; the shape is rotated by the phase that makes it most nearly real
    (theta = arg(sum psi^2)/2) and its real part kept.
    """
    values = record["values"]
    if record["eig"] is None:
        return float(record["freq"]), float(record["zeta"]), np.real(values).astype(float)
    lam = record["eig"]
    theta = 0.5 * np.angle(np.sum(values.astype(complex) ** 2))
    return abs(lam) / (2 * np.pi), -lam.real / abs(lam), np.real(values * np.exp(-1j * theta))
