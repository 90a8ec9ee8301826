"""Design variables of model tuning: bulk-data fields, linking, bounds, scaling; tuned bulk data.

A design variable names one or more bulk-data fields (paper sec. II: "continuous design variables
with side constraints, starting values, and scaling factors"):

- ``PBAR``/``PBEAM``/``PROD`` ``A``, ``I1``, ``I2``, ``J`` (PBEAM: every station scaled together);
- ``PBUSH`` ``K1``..``K6``; ``PELAS`` ``K``; ``CELAS2`` ``K`` (by element id);
- ``CONM2`` ``M``, ``I11``, ``I21``, ``I22``, ``I31``, ``I32``, ``I33`` (inertias in the basic frame,
  Nastran's sign convention: tensor off-diagonals are -I21, -I31, -I32);
- ``MAT1`` ``E``, ``G``; ``MAT8`` ``E1``, ``E2``, ``G12``, ``G1Z``, ``G2Z``; ``PSHELL`` ``T``.

Linking: the variable's value x is the first field's value; every linked field k keeps its ratio to
it, value_k(x) = value_k(x0) * x / x0, so left/right symmetric properties move together and fields of
different size move in proportion. Bounds default to x0 (1 -+ 0.2) (the paper's +-20 % side
constraints); the optimiser sees the scaled variable z = x / scale (default scale |x0|).

MAT1: the reader completes a blank G (or NU) from the other two at the deck's values, and a field
tuned alone leaves the others at those values. For the behaviour of a blank G (G following E with
NU fixed, as Nastran completes it) link E and G in one variable; E alone holds G and NU, so the
material leaves the isotropic relation G = E / 2(1 + NU) (and a CQUAD4 stiffness becomes rational
in E, which :mod:`structures.subassembly` then re-assembles at every design).
"""
from __future__ import annotations

import io
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from structures.common.errors import InputError, MissingReferenceError, card_message
from structures.common.files import write_text
from structures.common.nastran import read_pynastran
from structures.model import ElementSet, FEModel, Material, Property

#: Tunable fields per card.
TUNABLE = {
    "PBAR": ("A", "I1", "I2", "J"), "PBEAM": ("A", "I1", "I2", "J"), "PROD": ("A", "J"),
    "PBUSH": ("K1", "K2", "K3", "K4", "K5", "K6"), "PELAS": ("K",), "CELAS2": ("K",),
    "CONM2": ("M", "I11", "I21", "I22", "I31", "I32", "I33"),
    "MAT1": ("E", "G"), "MAT8": ("E1", "E2", "G12", "G1Z", "G2Z"), "PSHELL": ("T",),
}
_PROPERTY_CARDS = ("PBAR", "PBEAM", "PROD", "PBUSH", "PELAS", "PSHELL")
# CONM2 inertia field -> (row, col, sign) in the basic tensor
_INERTIA = {"I11": (0, 0, 1.0), "I21": (1, 0, -1.0), "I22": (1, 1, 1.0), "I31": (2, 0, -1.0),
            "I32": (2, 1, -1.0), "I33": (2, 2, 1.0)}
DEFAULT_BOUND = 0.2


@dataclass(frozen=True)
class FieldRef:
    """One bulk-data field: card name, card id and field name (e.g. ``PBAR 201 I1``)."""

    card: str
    card_id: int
    field: str

    def __post_init__(self):
        object.__setattr__(self, "card", str(self.card).upper())
        object.__setattr__(self, "field", str(self.field).upper())
        if self.card not in TUNABLE:
            raise InputError(card_message(f"card {self.card} cannot be a design variable.",
                                          card=self.card, card_id=self.card_id,
                                          fix=f"use one of {sorted(TUNABLE)}."))
        if self.field not in TUNABLE[self.card]:
            raise InputError(card_message(f"field {self.field!r} is not a tunable field of "
                                          f"{self.card}.", card=self.card, card_id=self.card_id,
                                          fix=f"use one of {list(TUNABLE[self.card])}."))

    def __str__(self) -> str:
        return f"{self.card} {self.card_id} {self.field}"


@dataclass(frozen=True)
class DesignVariable:
    """A continuous design variable driving one or more linked fields.

    Attributes
    ----------
    name : str
    fields : tuple of FieldRef
        The first field defines the variable's value; the others are linked in proportion.
    lower, upper : float, optional
        Side constraints on the value; default x0 (1 -+ 0.2).
    scale : float, optional
        The optimiser works on x / scale; default |x0|.
    """

    name: str
    fields: tuple
    lower: float | None = None
    upper: float | None = None
    scale: float | None = None

    def __post_init__(self):
        refs = tuple(f if isinstance(f, FieldRef) else FieldRef(*f) for f in self.fields)
        if not refs:
            raise InputError(f"design variable {self.name!r}: no fields. Fix: name at least one "
                             "(card, id, field).")
        if len(set(refs)) != len(refs):
            raise InputError(f"design variable {self.name!r}: a field is listed twice.")
        object.__setattr__(self, "fields", refs)
        if self.scale is not None and not self.scale > 0:
            raise InputError(f"design variable {self.name!r}: scale = {self.scale} must be > 0.")


def get_field(model: FEModel, ref: FieldRef) -> float:
    """The current value of a field in ``model``; MissingReferenceError if card or id is absent."""
    where = dict(card=ref.card, card_id=ref.card_id, filename=model.filename)
    if ref.card in _PROPERTY_CARDS:
        prop = model.properties.get(int(ref.card_id))
        if prop is None or prop.card != ref.card:
            raise MissingReferenceError(card_message(
                f"no {ref.card} with id {ref.card_id} in the model (design variable field "
                f"{ref.field}).", **where, fix="name a property card that the deck defines."))
        value = prop.fields.get(ref.field)
    elif ref.card in ("MAT1", "MAT8"):
        mat = model.materials.get(int(ref.card_id))
        if mat is None or mat.card != ref.card:
            raise MissingReferenceError(card_message(
                f"no {ref.card} with id {ref.card_id} in the model.", **where,
                fix="name a material card that the deck defines."))
        value = mat.fields.get(ref.field)
    elif ref.card == "CONM2":
        hit = np.flatnonzero(model.masses.eids == int(ref.card_id))
        if hit.size == 0:
            raise MissingReferenceError(card_message("no such CONM2 in the model.", **where,
                                                     fix="name a CONM2 element id of the deck."))
        if ref.field == "M":
            value = model.masses.mass[hit[0]]
        else:
            r, c, sign = _INERTIA[ref.field]
            value = sign * model.masses.inertia[hit[0], r, c]
    else:  # CELAS2
        es = model.elements.get("CELAS")
        hit = np.array([], int) if es is None else np.flatnonzero(es.eids == int(ref.card_id))
        if hit.size == 0 or np.isnan(es.data["k"][hit[0]]):
            raise MissingReferenceError(card_message("no such CELAS2 in the model.", **where,
                                                     fix="name a CELAS2 element id (CELAS1 takes "
                                                         "its K from PELAS: name the PELAS)."))
        value = es.data["k"][hit[0]]
    if value is None:
        raise InputError(card_message(f"field {ref.field} is blank, so it cannot be tuned.", **where,
                                      fix="give the field a value in the deck."))
    return float(value)


@dataclass(frozen=True)
class DesignSpace:
    """Design variables bound to the models of every configuration.

    Attributes
    ----------
    variables : tuple of DesignVariable
    x0, lower, upper, scale : (nvar,) start values, side constraints and scale factors.
    ratios : tuple of (nfields_v,) arrays, value of each linked field at x0 divided by x0.
    """

    variables: tuple
    x0: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    scale: np.ndarray
    ratios: tuple

    @property
    def names(self) -> list[str]:
        return [v.name for v in self.variables]

    def __len__(self) -> int:
        return len(self.variables)

    def to_scaled(self, x) -> np.ndarray:
        """z = x / scale."""
        return np.asarray(x, float) / self.scale

    def from_scaled(self, z) -> np.ndarray:
        """x = z * scale."""
        return np.asarray(z, float) * self.scale

    def check(self, x) -> np.ndarray:
        """``x`` as an array of the right length and inside the bounds, else InputError."""
        x = np.asarray(x, float)
        if x.shape != self.x0.shape:
            raise InputError(f"design vector of shape {x.shape}; {self.x0.size} variables "
                             f"{self.names}.")
        bad = np.flatnonzero((x < self.lower - 1e-12 * np.abs(self.lower))
                             | (x > self.upper + 1e-12 * np.abs(self.upper)))
        if bad.size:
            i = bad[0]
            raise InputError(f"design variable {self.names[i]!r} = {x[i]:.6g} is outside its bounds "
                             f"[{self.lower[i]:.6g}, {self.upper[i]:.6g}].")
        return x


def bind(variables, models) -> DesignSpace:
    """Check design variables against the models and fix their start values and bounds.

    Every field must exist (with a value) in at least one model; where it exists in several, the
    start values must agree. Bounds must contain the start value. All errors are raised here,
    before any solve.

    Parameters
    ----------
    variables : sequence of DesignVariable
    models : sequence of FEModel (one per configuration)

    Returns
    -------
    DesignSpace
    """
    variables = tuple(variables)
    names = [v.name for v in variables]
    if len(set(names)) != len(names):
        raise InputError(f"design variables: duplicate names {names}.")
    owner = {}
    x0, lo, hi, sc, ratios = [], [], [], [], []
    for var in variables:
        values = []
        for ref in var.fields:
            if ref in owner:
                raise InputError(f"design variables {owner[ref]!r} and {var.name!r} both drive "
                                 f"{ref}. Fix: a field belongs to one variable.")
            owner[ref] = var.name
            found = []
            errors = []
            for model in models:
                try:
                    found.append(get_field(model, ref))
                except MissingReferenceError as exc:
                    errors.append(str(exc))
            if not found:
                raise MissingReferenceError(f"design variable {var.name!r}: {errors[0]}")
            if not np.allclose(found, found[0], rtol=1e-9, atol=0.0):
                raise InputError(f"design variable {var.name!r}: {ref} has different values "
                                 f"{found} in the configurations. Fix: shared variables need equal "
                                 "start values (or use one variable per configuration).")
            values.append(found[0])
        start = values[0]
        if start == 0.0:
            raise InputError(f"design variable {var.name!r}: its first field {var.fields[0]} is 0; "
                             "linked scaling needs a non-zero start. Fix: give it a non-zero value.")
        lower = var.lower if var.lower is not None else min(start * (1 - DEFAULT_BOUND),
                                                            start * (1 + DEFAULT_BOUND))
        upper = var.upper if var.upper is not None else max(start * (1 - DEFAULT_BOUND),
                                                            start * (1 + DEFAULT_BOUND))
        if not lower <= start <= upper:
            raise InputError(f"design variable {var.name!r}: bounds [{lower:.6g}, {upper:.6g}] "
                             f"exclude the start value {start:.6g} of {var.fields[0]}. Fix: widen "
                             "the bounds or correct the deck.")
        if not lower < upper:
            raise InputError(f"design variable {var.name!r}: lower bound {lower} is not below the "
                             f"upper bound {upper}.")
        x0.append(start)
        lo.append(lower)
        hi.append(upper)
        sc.append(var.scale if var.scale is not None else abs(start))
        ratios.append(np.asarray(values) / start)
    return DesignSpace(variables, np.array(x0), np.array(lo), np.array(hi), np.array(sc),
                       tuple(ratios))


def field_values(space: DesignSpace, x) -> dict:
    """{FieldRef: value} of every linked field at design ``x``."""
    x = np.asarray(x, float)
    return {ref: float(x[i] * r) for i, var in enumerate(space.variables)
            for ref, r in zip(var.fields, space.ratios[i])}


def apply_design(model: FEModel, space: DesignSpace, x, *, only=None) -> FEModel:
    """A copy of ``model`` with the design's field values (fields absent from it are skipped).

    Parameters
    ----------
    model : FEModel
    space : DesignSpace
    x : (nvar,) design values
    only : iterable of int, optional
        Apply these variables only (the others keep the model's values).
    """
    keep = set(range(len(space))) if only is None else set(only)
    x = np.asarray(x, float)
    values = {ref: float(x[i] * r) for i, var in enumerate(space.variables) if i in keep
              for ref, r in zip(var.fields, space.ratios[i])}
    props, mats = dict(model.properties), dict(model.materials)
    mass, inertia = np.array(model.masses.mass), np.array(model.masses.inertia)
    celas = model.elements.get("CELAS")
    k_el = None if celas is None else np.array(celas.data["k"], float)
    for ref, value in values.items():
        cid = int(ref.card_id)
        if ref.card in _PROPERTY_CARDS:
            if cid in props and props[cid].card == ref.card:
                props[cid] = Property(cid, ref.card, {**props[cid].fields, ref.field: value})
        elif ref.card in ("MAT1", "MAT8"):
            if cid in mats and mats[cid].card == ref.card:
                mats[cid] = Material(cid, ref.card, {**mats[cid].fields, ref.field: value})
        elif ref.card == "CONM2":
            hit = model.masses.eids == cid
            if ref.field == "M":
                mass[hit] = value
            else:
                r, c, sign = _INERTIA[ref.field]
                inertia[hit, r, c] = inertia[hit, c, r] = sign * value
        elif k_el is not None:
            k_el[celas.eids == cid] = value
    elements = dict(model.elements)
    if k_el is not None:
        elements["CELAS"] = replace(celas, data={**celas.data, "k": k_el})
    return replace(model, properties=props, materials=mats, elements=elements,
                   masses=replace(model.masses, mass=mass, inertia=inertia))


def material_ids(prop: Property) -> set:
    """The material ids a property references (its MID, MID1 .. MID4 fields that are set)."""
    return {int(prop.fields[k]) for k in ("MID", "MID1", "MID2", "MID3", "MID4")
            if prop.fields.get(k)}


def affected_submodel(model: FEModel, space: DesignSpace, only=None) -> FEModel | None:
    """The model restricted to the elements and masses whose matrices the variables change.

    Used for sub-assembly: K(x) = K_rest + K_affected(x). Returns None when nothing in ``model``
    depends on the selected variables.
    """
    keep = range(len(space)) if only is None else only
    refs = [ref for i in keep for ref in space.variables[i].fields]
    pids = {int(r.card_id) for r in refs if r.card in _PROPERTY_CARDS}
    mids = {int(r.card_id) for r in refs if r.card in ("MAT1", "MAT8")}
    pids |= {pid for pid, p in model.properties.items() if material_ids(p) & mids}
    conm2 = {int(r.card_id) for r in refs if r.card == "CONM2"}
    celas2 = {int(r.card_id) for r in refs if r.card == "CELAS2"}
    elements = {}
    for kind, es in model.elements.items():
        sel = np.isin(es.pids, list(pids)) & (es.pids > 0)
        if kind == "CELAS":
            sel |= np.isin(es.eids, list(celas2)) & ~np.isnan(np.asarray(es.data["k"], float))
        if kind == "CMASS2":
            sel[:] = False
        if np.any(sel):
            elements[kind] = ElementSet(kind, es.eids[sel], es.pids[sel], es.nodes[sel],
                                        {k: np.asarray(v)[sel] for k, v in es.data.items()})
    msel = np.isin(model.masses.eids, list(conm2))
    if not elements and not np.any(msel):
        return None
    cm = model.masses
    masses = replace(cm, eids=cm.eids[msel], grid=cm.grid[msel], mass=cm.mass[msel],
                     offset=cm.offset[msel], inertia=cm.inertia[msel])
    return replace(model, elements=elements, masses=masses)


def element_groups(model: FEModel, space: DesignSpace) -> list:
    """The affected elements and CONM2s partitioned by the set of variables that change them.

    Two elements belong to one group when exactly the same design variables change their matrices
    (e.g. every skin CQUAD4 is changed by the skin thickness and the skin modulus), so each group's
    matrices are a function of its own variables only.

    Returns
    -------
    list of (variables, submodel): variables a tuple of variable indices (sorted), submodel the
    FEModel restricted to the group's elements and CONM2s; groups in a fixed order.
    """
    owners = {}
    for i in range(len(space)):
        sub = affected_submodel(model, space, only=[i])
        if sub is None:
            continue
        for kind, es in sub.elements.items():
            for eid in es.eids.tolist():
                owners.setdefault((kind, eid), set()).add(i)
        for eid in sub.masses.eids.tolist():
            owners.setdefault(("", eid), set()).add(i)
    by_vars = {}
    for key, own in owners.items():
        by_vars.setdefault(tuple(sorted(own)), []).append(key)
    groups = []
    for variables in sorted(by_vars):
        keys = by_vars[variables]
        elements = {}
        for kind, es in model.elements.items():
            sel = np.isin(es.eids, [eid for k, eid in keys if k == kind])
            if np.any(sel):
                elements[kind] = ElementSet(kind, es.eids[sel], es.pids[sel], es.nodes[sel],
                                            {k: np.asarray(v)[sel] for k, v in es.data.items()})
        cm = model.masses
        msel = np.isin(cm.eids, [eid for k, eid in keys if k == ""])
        masses = replace(cm, eids=cm.eids[msel], grid=cm.grid[msel], mass=cm.mass[msel],
                         offset=cm.offset[msel], inertia=cm.inertia[msel])
        groups.append((variables, replace(model, elements=elements, masses=masses)))
    return groups


# ------------------------------------------------------------------------------ writing bulk data
_PYNASTRAN_ATTR = {("PBAR", "A"): "A", ("PBAR", "I1"): "i1", ("PBAR", "I2"): "i2",
                   ("PBAR", "J"): "j", ("PBEAM", "A"): "A", ("PBEAM", "I1"): "i1",
                   ("PBEAM", "I2"): "i2", ("PBEAM", "J"): "j", ("PROD", "A"): "A",
                   ("PROD", "J"): "j", ("PELAS", "K"): "k", ("CELAS2", "K"): "k",
                   ("CONM2", "M"): "mass", ("MAT1", "E"): "e", ("MAT1", "G"): "g",
                   ("MAT8", "E1"): "e11", ("MAT8", "E2"): "e22", ("MAT8", "G12"): "g12",
                   ("MAT8", "G1Z"): "g1z", ("MAT8", "G2Z"): "g2z", ("PSHELL", "T"): "t"}


def _card_object(bdf, ref: FieldRef):
    cid = int(ref.card_id)
    table = (bdf.properties if ref.card in _PROPERTY_CARDS else
             bdf.materials if ref.card == "MAT1" else
             bdf.masses if ref.card == "CONM2" else
             bdf.elements if ref.card == "CELAS2" else None)
    if ref.card == "MAT8":
        obj = bdf.materials.get(cid)
    else:
        obj = table.get(cid) if table is not None else None
    if obj is None or obj.type != ref.card:
        raise MissingReferenceError(card_message(
            f"{ref.card} {cid} is not a card of the deck being written"
            + (f" (it is a {obj.type})" if obj is not None else "") + ".", card=ref.card,
            card_id=cid, fix="tuned PBARL sections cannot be written as PBAR fields; use PBAR."))
    return obj


def write_tuned_bdf(deck_in, deck_out, space: DesignSpace, x) -> Path:
    """Write the deck with the tuned field values (pyNastran), keeping every other card.

    Fields the deck does not contain (e.g. a fuel CONM2 of another configuration) are skipped.

    Parameters
    ----------
    deck_in, deck_out : path-like
    space : DesignSpace
    x : (nvar,) tuned design values
    """
    bdf = read_pynastran(deck_in)
    for ref, value in field_values(space, space.check(x)).items():
        try:
            obj = _card_object(bdf, ref)
        except MissingReferenceError:
            present = (ref.card in _PROPERTY_CARDS and int(ref.card_id) in bdf.properties) or \
                      (ref.card in ("MAT1", "MAT8") and int(ref.card_id) in bdf.materials) or \
                      (ref.card == "CONM2" and int(ref.card_id) in bdf.masses) or \
                      (ref.card == "CELAS2" and int(ref.card_id) in bdf.elements)
            if present:
                raise
            continue
        if ref.card == "PBUSH":
            k = list(obj.Ki) + [0.0] * (6 - len(obj.Ki))
            k[int(ref.field[1]) - 1] = value
            obj.Ki = k
        elif ref.card == "CONM2" and ref.field != "M":
            inertia = list(obj.I)
            inertia[["I11", "I21", "I22", "I31", "I32", "I33"].index(ref.field)] = value
            obj.I = np.array(inertia)
        elif ref.card == "PBEAM":
            attr = _PYNASTRAN_ATTR[(ref.card, ref.field)]
            old = np.asarray(getattr(obj, attr), float)
            mean = 0.5 * (old[0] + old[-1])
            setattr(obj, attr, (old * (value / mean)).tolist())
        else:
            setattr(obj, _PYNASTRAN_ATTR[(ref.card, ref.field)], value)
    text = io.StringIO()
    bdf.write_bdf(text, size=16, is_double=False, close=False)
    return write_text(text.getvalue(), Path(deck_out))
