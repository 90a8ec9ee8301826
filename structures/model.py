"""The FE model: frozen, validated dataclasses built from Nastran bulk data.

Elements of one kind are stored as stacked arrays (ids, connectivity, property ids) so that assembly
is vectorised; properties and materials are small frozen dataclasses keyed by id, so that a tuning
design variable (e.g. PBAR 201 field I1) maps to one field that :func:`dataclasses.replace` changes.

Frames: every position is in the basic frame. ``Grids.cd_axes[i]`` holds the displacement frame of
grid i as a (3, 3) matrix whose columns are that frame's unit vectors in basic, so that
``u_basic = cd_axes @ u_cd``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Mapping

import numpy as np

from structures.common.errors import InputError, MissingReferenceError, card_message
from structures.elements.shell import K6ROT_DEFAULT
from structures.singularity import EPZERO_DEFAULT


def _frozen_array(values, dtype, shape_tail=()) -> np.ndarray:
    arr = np.array(values, dtype=dtype)
    if shape_tail and arr.size == 0:
        arr = arr.reshape((0,) + tuple(shape_tail))
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True)
class Grids:
    """Structural grid points.

    Attributes
    ----------
    ids : (n,) int
    xyz : (n, 3) float, basic-frame positions.
    cd_axes : (n, 3, 3) float, displacement-frame axes (columns) in basic.
    cd : (n,) int, the CD coordinate-system id (for messages and output).
    ps : (n,) int, permanent single-point constraints as a bit mask (bit c-1 for component c).
    """

    ids: np.ndarray
    xyz: np.ndarray
    cd_axes: np.ndarray
    cd: np.ndarray
    ps: np.ndarray

    def __post_init__(self):
        object.__setattr__(self, "ids", _frozen_array(self.ids, np.int64))
        object.__setattr__(self, "xyz", _frozen_array(self.xyz, float, (3,)))
        object.__setattr__(self, "cd_axes", _frozen_array(self.cd_axes, float, (3, 3)))
        object.__setattr__(self, "cd", _frozen_array(self.cd, np.int64))
        object.__setattr__(self, "ps", _frozen_array(self.ps, np.int64))
        if len(np.unique(self.ids)) != len(self.ids):
            raise InputError(card_message("duplicate grid ids.", card="GRID",
                                          fix="give every GRID a unique id."))
        order = np.argsort(self.ids)
        object.__setattr__(self, "_index", dict(zip(self.ids[order].tolist(), order.tolist())))

    def __len__(self) -> int:
        return len(self.ids)

    def index(self, grid_ids, *, card: str = "", card_id=None, filename: str | None = None) -> np.ndarray:
        """Row index of each grid id; raise MissingReferenceError naming the referring card."""
        ids = np.atleast_1d(np.asarray(grid_ids, dtype=np.int64))
        try:
            return np.array([self._index[int(g)] for g in ids.ravel()], dtype=np.int64).reshape(ids.shape)
        except KeyError as exc:
            raise MissingReferenceError(card_message(
                f"grid {exc.args[0]} is referenced but not defined.", card=card or None,
                card_id=card_id, filename=filename,
                fix=f"add GRID {exc.args[0]} or correct the reference.")) from None


@dataclass(frozen=True)
class Material:
    """MAT1 (isotropic), MAT2 (anisotropic shell) or MAT8 (orthotropic shell).

    ``fields`` keeps the card's values by their Nastran field names (``E``, ``G``, ``NU``, ``RHO``
    for MAT1; ``G11``..``G33`` for MAT2; ``E1``, ``E2``, ``NU12``, ``G12``, ``G1Z``, ``G2Z`` for MAT8).
    """

    mid: int
    card: str
    fields: Mapping[str, float]

    def __post_init__(self):
        object.__setattr__(self, "fields", MappingProxyType(dict(self.fields)))

    @property
    def rho(self) -> float:
        return float(self.fields.get("RHO", 0.0) or 0.0)

    def isotropic(self) -> tuple[float, float, float]:
        """(E, G, nu) of a MAT1, completing a blank one as Nastran does (G = E / (2 (1 + nu)))."""
        if self.card != "MAT1":
            raise InputError(card_message(f"a {self.card} is used where a MAT1 is required.",
                                          card=self.card, card_id=self.mid,
                                          fix="reference a MAT1 from bar, rod and beam properties."))
        e, g, nu = (self.fields.get(k) for k in ("E", "G", "NU"))
        if e is None and g is None:
            raise InputError(card_message("E and G are both blank.", card="MAT1", card_id=self.mid,
                                          fix="give E (and NU or G)."))
        if e is None:
            e = 2.0 * (1.0 + (nu or 0.0)) * g
        elif g is None:
            g = e / (2.0 * (1.0 + (nu or 0.0)))
        elif nu is None:
            nu = e / (2.0 * g) - 1.0
        return float(e), float(g), float(nu or 0.0)


@dataclass(frozen=True)
class Property:
    """An element property card (PBAR, PBARL, PBEAM, PROD, PELAS, PBUSH, PSHELL).

    ``fields`` holds the section values the element formulation uses under the Nastran field names
    (PBAR: ``A``, ``I1``, ``I2``, ``I12``, ``J``, ``NSM``, ``K1``, ``K2``; PSHELL: ``T``, ``MID1``...),
    so that a tuning design variable can name them.
    """

    pid: int
    card: str
    fields: Mapping[str, float]

    def __post_init__(self):
        object.__setattr__(self, "fields", MappingProxyType(dict(self.fields)))

    def get(self, name: str, default: float = 0.0) -> float:
        value = self.fields.get(name)
        return default if value is None else value


@dataclass(frozen=True)
class ElementSet:
    """All elements of one card type.

    Attributes
    ----------
    card : str
        ``CBAR``, ``CBEAM``, ``CROD``, ``CELAS``, ``CBUSH``, ``CQUAD4``, ``CTRIA3``.
    eids : (ne,) int
    pids : (ne,) int (0 where the card has no property, e.g. CELAS2)
    nodes : (ne, nn) int grid ids (0 = none, e.g. a grounded spring)
    data : mapping of extra per-element arrays (orientation vectors, offsets, pin flags, ...)
    """

    card: str
    eids: np.ndarray
    pids: np.ndarray
    nodes: np.ndarray
    data: Mapping[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "eids", _frozen_array(self.eids, np.int64))
        object.__setattr__(self, "pids", _frozen_array(self.pids, np.int64))
        nodes = np.array(self.nodes, dtype=np.int64)
        if nodes.ndim == 1:
            nodes = nodes.reshape(len(self.eids), -1)
        nodes.setflags(write=False)
        object.__setattr__(self, "nodes", nodes)
        frozen = {}
        for key, value in dict(self.data).items():
            arr = np.array(value)
            arr.setflags(write=False)
            frozen[key] = arr
        object.__setattr__(self, "data", MappingProxyType(frozen))

    def __len__(self) -> int:
        return len(self.eids)


@dataclass(frozen=True)
class ConcentratedMass:
    """CONM2 masses, with offsets and inertias already expressed in the basic frame.

    Attributes
    ----------
    eids : (nm,) int
    grid : (nm,) int
    mass : (nm,) float
    offset : (nm, 3) float, basic-frame vector from the grid to the centre of mass.
    inertia : (nm, 3, 3) float, inertia tensor about the centre of mass, basic axes
        (Nastran's CONM2 convention: off-diagonals of the tensor are -I21, -I31, -I32).
    """

    eids: np.ndarray
    grid: np.ndarray
    mass: np.ndarray
    offset: np.ndarray
    inertia: np.ndarray

    def __post_init__(self):
        object.__setattr__(self, "eids", _frozen_array(self.eids, np.int64))
        object.__setattr__(self, "grid", _frozen_array(self.grid, np.int64))
        object.__setattr__(self, "mass", _frozen_array(self.mass, float))
        object.__setattr__(self, "offset", _frozen_array(self.offset, float, (3,)))
        object.__setattr__(self, "inertia", _frozen_array(self.inertia, float, (3, 3)))

    def __len__(self) -> int:
        return len(self.eids)

    def with_mass(self, eid: int, mass: float) -> "ConcentratedMass":
        """A copy with CONM2 ``eid``'s mass replaced (used by tuning)."""
        from dataclasses import replace
        values = np.array(self.mass)
        values[self.eids == eid] = mass
        return replace(self, mass=values)


@dataclass(frozen=True)
class RigidElement:
    """RBE2, RBAR or RBE3 as read from the deck.

    ``independent`` and ``dependent`` are tuples of (grid, components-string) pairs; ``weights`` is
    the RBE3 weight per independent entry (empty for RBE2/RBAR).
    """

    eid: int
    card: str
    independent: tuple
    dependent: tuple
    weights: tuple = ()


@dataclass(frozen=True)
class FEModel:
    """A validated structural model read from one bulk-data deck.

    ``k6rot``, ``epzero`` and ``autospc`` are the deck's PARAM K6ROT (shell drilling stiffness,
    MSC default 100.), PARAM EPZERO (grid point singularity ratio, default 1e-8) and PARAM / case
    control AUTOSPC (default YES); see :mod:`structures.singularity`.
    """

    filename: str
    grids: Grids
    elements: Mapping[str, ElementSet]
    properties: Mapping[int, Property]
    materials: Mapping[int, Material]
    masses: ConcentratedMass
    rigid: tuple
    spc: tuple  # (grid, components) pairs of the selected SPC set, components as a bit mask
    suport: tuple
    wtmass: float = 1.0
    coupmass: int = -1
    eigrl_nd: int | None = None
    units: str = "deck"
    k6rot: float = K6ROT_DEFAULT
    epzero: float = EPZERO_DEFAULT
    autospc: bool = True

    def __post_init__(self):
        object.__setattr__(self, "elements", MappingProxyType(dict(self.elements)))
        object.__setattr__(self, "properties", MappingProxyType(dict(self.properties)))
        object.__setattr__(self, "materials", MappingProxyType(dict(self.materials)))
        if not self.wtmass > 0:
            raise InputError(card_message(f"WTMASS = {self.wtmass} must be positive.", card="PARAM",
                                          card_id="WTMASS", filename=self.filename,
                                          fix="set PARAM,WTMASS to a positive factor (default 1.0)."))
        for name, value in (("K6ROT", self.k6rot), ("EPZERO", self.epzero)):
            if not (np.isfinite(value) and value >= 0):
                raise InputError(card_message(f"{name} = {value} must be a non-negative number.",
                                              card="PARAM", card_id=name, filename=self.filename,
                                              fix=f"set PARAM,{name} to a value >= 0 or remove it."))

    def property(self, pid: int, *, card: str, eid: int) -> Property:
        """The property ``pid`` referenced by element ``eid``; a clear error when missing."""
        try:
            return self.properties[int(pid)]
        except KeyError:
            raise MissingReferenceError(card_message(
                f"property {pid} is referenced but not defined.", card=card, card_id=eid,
                filename=self.filename, fix=f"add the property card with id {pid}.")) from None

    def material(self, mid: int, *, card: str, pid: int) -> Material:
        """The material ``mid`` referenced by property ``pid``; a clear error when missing."""
        try:
            return self.materials[int(mid)]
        except KeyError:
            raise MissingReferenceError(card_message(
                f"material {mid} is referenced but not defined.", card=card, card_id=pid,
                filename=self.filename, fix=f"add MAT1/MAT2/MAT8 {mid}.")) from None

    def with_property(self, pid: int, **fields: float) -> "FEModel":
        """A copy with some fields of property ``pid`` replaced (used by tuning)."""
        old = self.property(pid, card="(design variable)", eid=pid)
        props = dict(self.properties)
        props[pid] = Property(pid, old.card, {**old.fields, **fields})
        from dataclasses import replace
        return replace(self, properties=props)
