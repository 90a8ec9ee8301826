"""Reference and value checks of an FE model, run when it is read (before any solve).

Each check raises the project's error naming the file, the card, the id and the fix, so that a bad
deck fails early and nothing is half-written. Values: every number must be finite and at most
HUGE (1e40) in magnitude; sections, moduli and densities must not be negative (area and shell
thickness positive); Poisson's ratio lies in (-1, 0.5]. Geometry: rods have a length; shells have
an area and a convex outline (a CQUAD4 is projected on its mean plane, normal d13 x d24 as in the
element) and are not folded (corners no farther from the mean plane than the mean half-diagonal).
The element kernels keep their own checks for callers that bypass the reader.
"""
from __future__ import annotations

import numbers

import numpy as np

from structures.common.errors import InputError, card_message
from structures.model import FEModel

_PROPERTY_OF = {"CBAR": ("PBAR", "PBEAM"), "CBEAM": ("PBAR", "PBEAM"), "CROD": ("PROD",),
                "CELAS": ("PELAS",), "CBUSH": ("PBUSH",), "CQUAD4": ("PSHELL",),
                "CTRIA3": ("PSHELL",)}
_SECTION_FIELDS = {"PBAR": ("A",), "PBEAM": ("A",), "PROD": ("A",), "PSHELL": ("T",)}
#: Fields that must not be negative, per card.
_NON_NEGATIVE = {"PBAR": ("I1", "I2", "J"), "PBEAM": ("I1", "I2", "J"), "PROD": ("J",),
                 "PSHELL": ("12I/T**3", "TS/T"), "MAT1": ("E", "G", "RHO"),
                 "MAT2": ("RHO",), "MAT8": ("G12", "G1Z", "G2Z", "RHO")}
#: Elements whose grid fields may be blank (0): a grounded end.
_GROUNDED = ("CELAS", "CMASS2", "CBUSH")
#: Per-element data that must be finite and at most HUGE (others use NaN as a "blank" marker).
_FINITE_DATA = ("v", "wa", "wb", "theta", "zoffset", "s")
#: Largest magnitude of an input value: no unit system needs more, and element matrices take
#: products such as E T^3 or m r^2 that overflow double precision (1.8e308) from about 1e100 on.
HUGE = 1e40
#: A CQUAD4 whose corners lie farther from its mean plane than this fraction of its mean
#: half-diagonal is folded, not warped (Nastran only warns above a warping coefficient of 0.05).
FOLDED_WARP = 1.0


def _sane(values) -> np.ndarray:
    """True where a value is finite and at most HUGE in magnitude."""
    return np.abs(np.asarray(values, float)) <= HUGE  # False for NaN and inf


def _fail(problem: str, card: str, card_id, filename: str, fix: str) -> InputError:
    return InputError(card_message(problem, card=card, card_id=card_id, filename=filename,
                                   fix=fix))


def _check_fields(card: str, cid, fields, filename: str) -> None:
    """Every numeric field finite and at most HUGE; the card's non-negative fields not
    negative."""
    for name, value in fields.items():
        if isinstance(value, numbers.Real) and not _sane(value):
            raise _fail(f"{name} = {value} is not a finite number of at most {HUGE:g}.", card,
                        cid, filename, f"give {card} {cid} a real value of {name}.")
    for name in _NON_NEGATIVE.get(card, ()):
        value = fields.get(name)
        if value is not None and value < 0:
            raise _fail(f"{name} = {value} is negative.", card, cid, filename,
                        f"give {card} {cid} a {name} >= 0.")


def _check_material(mat, filename: str) -> None:
    f = mat.fields
    _check_fields(mat.card, mat.mid, f, filename)
    if mat.card == "MAT1":
        if f.get("E") is None and f.get("G") is None:
            raise _fail("E and G are both blank.", "MAT1", mat.mid, filename,
                        "give E (and NU or G).")
        nu = f.get("NU")
        if nu is not None and not -1.0 < nu <= 0.5:
            raise _fail(f"NU = {nu} lies outside (-1, 0.5].", "MAT1", mat.mid, filename,
                        "give Poisson's ratio -1 < NU <= 0.5.")
    elif mat.card == "MAT8":
        for name in ("E1", "E2"):
            value = f.get(name)
            if value is None or not value > 0:
                raise _fail(f"{name} = {value} must be positive.", "MAT8", mat.mid, filename,
                            f"give MAT8 {mat.mid} a positive {name}.")


def _check_property(model: FEModel, card: str, eid: int, pid: int) -> None:
    prop = model.property(pid, card=card, eid=eid)
    if prop.card not in _PROPERTY_OF[card]:
        needs = " or ".join(_PROPERTY_OF[card])
        raise _fail(f"references {prop.card} {pid}; {card} needs {needs}.", card, eid,
                    model.filename, "correct the PID field.")
    for name in _SECTION_FIELDS.get(prop.card, ()):
        value = prop.fields.get(name)
        if value is None or not value > 0:
            raise _fail(f"{name} = {value} must be positive.", prop.card, pid, model.filename,
                        f"give {prop.card} {pid} a positive {name}.")
    for key in ("MID", "MID1", "MID2", "MID3", "MID4"):
        mid = prop.fields.get(key)
        if mid:
            model.material(mid, card=prop.card, pid=pid)


def _check_section(prop, filename: str) -> None:
    f = prop.fields
    _check_fields(prop.card, prop.pid, f, filename)
    if prop.card in ("PBAR", "PBEAM"):
        i1, i2, i12 = (f.get(k) or 0.0 for k in ("I1", "I2", "I12"))
        if i1 * i2 < i12 * i12:
            raise _fail(f"I1*I2 = {i1 * i2:g} is less than I12**2 = {i12 * i12:g}.", prop.card,
                        prop.pid, filename, "give I1*I2 >= I12**2 (a real cross-section).")
    elif prop.card == "PSHELL":
        mid = {k: f.get(k) or 0 for k in ("MID1", "MID2", "MID4")}
        if not mid["MID1"] and not mid["MID2"]:
            raise _fail("MID1 and MID2 are both blank.", "PSHELL", prop.pid, filename,
                        "give MID1 (membrane) and/or MID2 (bending).")
        if mid["MID2"] < 0:
            raise _fail(f"MID2 = {mid['MID2']} (plane strain) is not supported.", "PSHELL",
                        prop.pid, filename, "use a positive MID2 or leave it blank.")
        if mid["MID4"] and not (mid["MID1"] and mid["MID2"]):
            raise _fail("MID4 requires both MID1 and MID2.", "PSHELL", prop.pid, filename,
                        "blank MID4 or give MID1 and MID2.")


def _check_rods(model: FEModel, es) -> None:
    xyz = model.grids.xyz[model.grids.index(es.nodes[:, :2])]
    length = np.linalg.norm(xyz[:, 1] - xyz[:, 0], axis=1)
    size = np.abs(xyz).max(axis=(1, 2))
    for e in np.flatnonzero(length <= 1e-12 * size):
        raise _fail("zero length: its two grids coincide.", es.card, es.eids[e], model.filename,
                    "separate the grids or remove the element.")


def _check_shells(model: FEModel, es) -> None:
    """Zero area, concave or twisted outline (grid order), folded CQUAD4 (see module docstring)."""
    xyz = model.grids.xyz[model.grids.index(es.nodes)]
    nn = xyz.shape[1]
    if nn == 4:
        d13, d24 = xyz[:, 2] - xyz[:, 0], xyz[:, 3] - xyz[:, 1]
        normal = np.cross(d13, d24)
        diag = 0.5 * (np.linalg.norm(d13, axis=1) + np.linalg.norm(d24, axis=1))
    else:
        normal = np.cross(xyz[:, 1] - xyz[:, 0], xyz[:, 2] - xyz[:, 0])
        diag = np.linalg.norm(xyz[:, 1] - xyz[:, 0], axis=1)
    twice_area = np.linalg.norm(normal, axis=1)
    flat = twice_area <= 1e-12 * diag ** 2
    unit = normal / np.where(flat, 1.0, twice_area)[:, None]
    edges = np.roll(xyz, -1, axis=1) - xyz
    turn = np.einsum("enk,ek->en", np.cross(edges, np.roll(edges, -1, axis=1)), unit)
    concave = np.any(turn <= 1e-12 * diag[:, None] ** 2, axis=1)
    height = np.abs(np.einsum("enk,ek->en", xyz - xyz.mean(axis=1, keepdims=True), unit)).max(1)
    folded = height > FOLDED_WARP * 0.5 * diag
    for e in np.flatnonzero(flat | concave | folded):
        if flat[e]:
            problem = "zero area (coincident or collinear grids, or parallel diagonals)."
        elif folded[e]:
            problem = (f"folded: its corners lie {height[e]:g} from the mean plane, more than "
                       f"{FOLDED_WARP:g} x the mean half-diagonal {0.5 * diag[e]:g}.")
        else:
            problem = "concave or twisted outline (an interior angle of 180 degrees or more)."
        raise _fail(problem, es.card, es.eids[e], model.filename,
                    "give the grids in order round the perimeter, without repeats, "
                    "and check their coordinates.")
    t = np.asarray(es.data["t_nodal"], float)
    for e in np.flatnonzero(np.any((~np.isnan(t) & ~_sane(t)) | (t <= 0), axis=1)):
        raise _fail(f"corner thicknesses T1..T{nn} = {t[e].tolist()} must be positive and at "
                    f"most {HUGE:g}.", es.card,
                    es.eids[e], model.filename, "give positive corner thicknesses or leave them "
                    "blank (PSHELL T).")


def _check_element_values(model: FEModel, es) -> None:
    for key in _FINITE_DATA:
        if key not in es.data:
            continue
        values = np.asarray(es.data[key], float).reshape(len(es), -1)
        for e in np.flatnonzero(~np.all(_sane(values), axis=1)):
            raise _fail(f"a field holds a non-finite or huge number ({key} = "
                        f"{values[e].tolist()}).", es.card, es.eids[e], model.filename,
                        "give real values.")
    if es.card == "CELAS":
        k = np.asarray(es.data["k"], float)
        for e in np.flatnonzero((es.pids == 0) & ~_sane(k)):
            raise _fail(f"stiffness K = {k[e]} is not a finite number of at most {HUGE:g}.",
                        "CELAS2", es.eids[e], model.filename, "give a real stiffness.")
    if es.card == "CMASS2":
        for eid, m in zip(es.eids, es.data["mass"]):
            if not (_sane(m) and m > 0):
                raise _fail(f"mass {m} is not positive.", "CMASS2", eid, model.filename,
                            "give a positive mass (or remove the card).")


def validate_model(model: FEModel) -> None:
    """Check every reference and value an assembly will use; raise on the first problem."""
    grids = model.grids
    bad = ~np.all(_sane(grids.xyz), axis=1) | ~np.all(np.isfinite(grids.cd_axes), axis=(1, 2))
    for g in np.flatnonzero(bad):
        raise _fail(f"position {grids.xyz[g].tolist()} or displacement frame CD={grids.cd[g]} is "
                    f"not finite (or beyond {HUGE:g}).", "GRID", grids.ids[g], model.filename,
                    "give real coordinates and a valid (non-degenerate) coordinate system.")
    cm = model.masses
    bad = ~(_sane(cm.mass) & np.all(_sane(cm.offset), axis=1)
            & np.all(_sane(cm.inertia), axis=(1, 2)))
    for m in np.flatnonzero(bad):
        raise _fail(f"mass {cm.mass[m]}, offset or inertia exceeds {HUGE:g}.", "CONM2", cm.eids[m],
                    model.filename, "give real values.")
    for mat in model.materials.values():
        _check_material(mat, model.filename)
    for prop in model.properties.values():
        _check_section(prop, model.filename)
    for card, es in model.elements.items():
        # Whole-array checks; the first failing element (in card order) is the one named.
        known = np.isin(es.nodes, grids.ids) | ((es.nodes == 0) if card in _GROUNDED else False)
        for r in np.flatnonzero(~np.all(known, axis=1))[:1]:
            row = es.nodes[r]
            grids.index(row[row != 0] if card in _GROUNDED else row, card=card,
                        card_id=es.eids[r], filename=model.filename)
        if card in _PROPERTY_OF:
            _, first = np.unique(es.pids, return_index=True)
            for r in np.sort(first):                 # each property once, at its first element
                if card == "CELAS" and es.pids[r] == 0:
                    continue
                _check_property(model, card, es.eids[r], es.pids[r])
        _check_element_values(model, es)
        if card == "CROD":
            _check_rods(model, es)
        elif card in ("CQUAD4", "CTRIA3"):
            _check_shells(model, es)
    for elem in model.rigid:
        for gid, _ in elem.independent + elem.dependent:
            grids.index([gid], card=elem.card, card_id=elem.eid, filename=model.filename)
    for gid, _ in model.spc + model.suport:
        grids.index([gid], card="SPC", card_id=gid, filename=model.filename)
