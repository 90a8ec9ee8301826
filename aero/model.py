"""Aerodynamic model from Nastran bulk data: reference values, CAERO1 panels, splines, Mach-k list.

:func:`read_aero_model` reads AERO/AEROS, CAERO1, PAERO1, AEFACT, SET1, SPLINE1, SPLINE2 and
MKAERO1/MKAERO2 through pyNastran into frozen dataclasses.

Frames. The doublet-lattice method takes the free stream along +x of the aerodynamic coordinate
system ACSID (AERO field 2), so the box mesh (:attr:`AeroModel.mesh`) is built in the ACSID frame.
CAERO1 corner points P1/P4 are given in the panel's CP frame and converted to basic and then to
ACSID; the chord lengths X12/X43 lie along the ACSID x axis (Nastran Quick Reference Guide, CAERO1).
When ACSID = 0 the ACSID frame is the basic frame. :meth:`AeroModel.to_basic` maps mesh points back.
Structural grid positions are kept in the basic frame.

Reduced frequency everywhere is Nastran's k = omega * b / V with b = REFC / 2.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from aero.panels import BoxMesh, caero1_boxes, concat
from structures.common.nastran import read_pynastran
from structures.common.errors import (InputError, MissingReferenceError, UnsupportedCardError,
                                      card_message)

#: Aerodynamic cards whose effect on the forces this project does not model.
UNSUPPORTED_AERO_CARDS = frozenset({
    "CAERO2", "CAERO3", "CAERO4", "CAERO5", "CAERO7", "BODY7", "PAERO2", "PAERO3", "PAERO4",
    "PAERO5", "PAERO7", "SPLINE3", "SPLINE4", "SPLINE5", "SPLINE6", "SPLINE7", "SPLRELX", "AECOMP",
    "AESURF", "AESURFS", "AELINK", "MONPNT1", "CSSCHD", "AEPRESS", "AEFORCE", "SET2",
})
SPLINE_USAGES = ("BOTH", "DISP", "FORCE")
#: Sanity bound on the number of boxes of a deck: the doublet-lattice AIC of n boxes takes
#: 16 n^2 bytes (40 GB at 50,000), so more boxes are a typing error in NSPAN/NCHORD or an AEFACT.
MAX_BOXES = 50_000


def _frozen(values, dtype=float, shape_tail=()) -> np.ndarray:
    arr = np.array(values, dtype=dtype).reshape((-1, *shape_tail)) if shape_tail else \
        np.array(values, dtype=dtype).reshape(-1)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True)
class Frame:
    """A rectangular frame: ``origin`` (3,) in basic and ``axes`` (3, 3) whose rows are the unit
    x, y, z axes in basic. A point p in the frame is ``origin + p @ axes`` in basic."""

    cid: int
    origin: np.ndarray
    axes: np.ndarray
    filename: str | None = None

    def __post_init__(self):
        origin = _frozen(self.origin)
        axes = np.array(self.axes, dtype=float).reshape(3, 3)
        if origin.shape != (3,) or not np.all(np.isfinite(origin)) or \
                not np.allclose(axes @ axes.T, np.eye(3), atol=1e-9):
            raise InputError(card_message("coordinate system is not a finite rectangular "
                                          "orthonormal frame.", card="CORD2R", card_id=self.cid,
                                          filename=self.filename,
                                          fix="use a CORD2R/CORD1R (rectangular) system with "
                                              "distinct, finite points A, B, C here."))
        axes.setflags(write=False)
        object.__setattr__(self, "origin", origin)
        object.__setattr__(self, "axes", axes)

    def to_basic(self, points: np.ndarray) -> np.ndarray:
        """Points (..., 3) in this frame -> basic (..., 3)."""
        return self.origin + np.asarray(points, dtype=float) @ self.axes

    def from_basic(self, points: np.ndarray) -> np.ndarray:
        """Points (..., 3) in basic -> this frame (..., 3)."""
        return (np.asarray(points, dtype=float) - self.origin) @ self.axes.T


BASIC = Frame(0, np.zeros(3), np.eye(3))


@dataclass(frozen=True)
class Caero1Panel:
    """One CAERO1 lifting surface, corner data in the ACSID frame.

    ``p1``, ``p4`` (3,) are the leading-edge corners; ``x12``, ``x43`` the root and tip chords along
    the ACSID x axis; ``span_fractions`` (nspan+1,) and ``chord_fractions`` (nchord+1,) run 0..1
    (uniform, or from AEFACT LSPAN/LCHORD). ``box_ids`` (nspan*nchord,) are EID, EID+1, ...
    """

    eid: int
    pid: int
    cp: int
    igid: int
    p1: np.ndarray
    x12: float
    p4: np.ndarray
    x43: float
    span_fractions: np.ndarray
    chord_fractions: np.ndarray
    filename: str | None = None

    def __post_init__(self):
        for name in ("p1", "p4", "span_fractions", "chord_fractions"):
            object.__setattr__(self, name, _frozen(getattr(self, name)))
        for name, frac in (("span", self.span_fractions), ("chord", self.chord_fractions)):
            if frac.size < 2 or abs(frac[0]) > 1e-9 or abs(frac[-1] - 1.0) > 1e-9 or \
                    np.any(np.diff(frac) <= 0):
                raise InputError(card_message(
                    f"{name}wise division fractions {frac.tolist()} must increase from 0.0 to 1.0.",
                    card="CAERO1", card_id=self.eid, filename=self.filename,
                    fix=f"correct NSPAN/NCHORD or the AEFACT referenced by L{name.upper()}."))

    @property
    def nspan(self) -> int:
        return self.span_fractions.size - 1

    @property
    def nchord(self) -> int:
        return self.chord_fractions.size - 1

    @property
    def box_ids(self) -> np.ndarray:
        return np.arange(self.eid, self.eid + self.nspan * self.nchord)


@dataclass(frozen=True)
class Spline:
    """A SPLINE1 (``kind="IPS"``, infinite-plate surface spline) or SPLINE2 (``kind="BEAM"``).

    ``grid_ids`` (ng,) are the SET1 grids, ``grid_xyz`` (ng, 3) their basic positions. ``dz`` is the
    linear attachment flexibility; SPLINE2 only: ``dtor`` = EI/GJ, ``dthx``/``dthy`` rotational
    attachment flexibilities (negative = rotation not attached), ``frame`` its CID system.
    """

    eid: int
    kind: str
    caero: int
    box1: int
    box2: int
    setg: int
    grid_ids: np.ndarray
    grid_xyz: np.ndarray
    dz: float = 0.0
    usage: str = "BOTH"
    dtor: float = 1.0
    dthx: float = 0.0
    dthy: float = 0.0
    frame: Frame = field(default=BASIC)
    filename: str | None = None

    def __post_init__(self):
        card = "SPLINE1" if self.kind == "IPS" else "SPLINE2"
        where = dict(card=card, card_id=self.eid, filename=self.filename)
        object.__setattr__(self, "grid_ids", _frozen(self.grid_ids, dtype=int))
        object.__setattr__(self, "grid_xyz", _frozen(self.grid_xyz, shape_tail=(3,)))
        if self.kind not in ("IPS", "BEAM"):
            raise InputError(card_message(f"spline kind {self.kind!r} unknown.", **where,
                                          fix="use 'IPS' or 'BEAM'."))
        if self.usage not in SPLINE_USAGES:
            raise InputError(card_message(f"USAGE={self.usage!r} unknown.", **where,
                                          fix=f"use one of {SPLINE_USAGES}."))
        if self.box2 < self.box1:
            raise InputError(card_message(f"BOX2={self.box2} < BOX1={self.box1}.", **where,
                                          fix="give BOX1 <= BOX2."))
        if not (self.dz >= 0 and 0 < self.dtor < np.inf and np.isfinite(self.dz + self.dthx
                                                                          + self.dthy)):
            raise InputError(card_message(
                f"DZ={self.dz} must be >= 0, DTOR={self.dtor} > 0 and DTHX={self.dthx}, "
                f"DTHY={self.dthy} finite.", **where, fix="correct the fields."))
        if self.grid_ids.size == 0 or self.grid_xyz.shape != (self.grid_ids.size, 3):
            raise InputError(card_message("the spline lists no structural grid points.", **where,
                                          fix=f"list grids on the SET1 {self.setg} it references."))

    @property
    def card(self) -> str:
        return "SPLINE1" if self.kind == "IPS" else "SPLINE2"


@dataclass(frozen=True)
class AeroModel:
    """The aerodynamic model of one deck (see module docstring for frames).

    ``mesh`` is the :class:`aero.panels.BoxMesh` of all CAERO1 boxes in the ACSID frame;
    ``mach_k`` (n, 2) the MKAERO Mach / reduced-frequency pairs in card order (within an MKAERO1
    card Mach-major). ``symxz`` = +1 symmetric, -1 antisymmetric, 0 none (AERO SYMXZ).
    """

    filename: str
    aero_frame: Frame
    refc: float
    rhoref: float
    velocity: float | None
    symxz: int
    symxy: int
    panels: tuple
    splines: tuple
    mesh: BoxMesh
    mach_k: np.ndarray

    def __post_init__(self):
        if not 0 < self.refc < np.inf or not 0 < self.rhoref < np.inf:
            raise InputError(card_message(f"REFC={self.refc} and RHOREF={self.rhoref} must be "
                                          "positive and finite.", card="AERO",
                                          filename=self.filename,
                                          fix="give the reference chord and density."))
        if self.symxz not in (-1, 0, 1) or self.symxy not in (-1, 0, 1):
            raise InputError(card_message(f"SYMXZ={self.symxz}, SYMXY={self.symxy} must be -1, "
                                          "0 or 1.", card="AERO", filename=self.filename,
                                          fix="correct the symmetry flags."))
        mk = np.array(self.mach_k, dtype=float).reshape(-1, 2)
        mk.setflags(write=False)
        object.__setattr__(self, "mach_k", mk)

    @property
    def machs(self) -> np.ndarray:
        """Distinct MKAERO Mach numbers, sorted (m,)."""
        return np.unique(self.mach_k[:, 0])

    @property
    def ks(self) -> np.ndarray:
        """Distinct MKAERO reduced frequencies k = omega*b/V, b = REFC/2, sorted (nk,)."""
        return np.unique(self.mach_k[:, 1])

    def panel(self, eid: int) -> Caero1Panel:
        """The CAERO1 panel with id ``eid``."""
        for pan in self.panels:
            if pan.eid == eid:
                return pan
        raise MissingReferenceError(card_message(
            f"no CAERO1 {eid}.", card="CAERO1", card_id=eid, filename=self.filename,
            fix=f"use one of {[p.eid for p in self.panels]}."))

    def to_basic(self, points: np.ndarray) -> np.ndarray:
        """Mesh points (..., 3) in the ACSID frame -> basic."""
        return self.aero_frame.to_basic(points)


def _frame(bdf, cid: int, card: str, card_id, filename: str) -> Frame:
    if cid in (0, None):
        return BASIC
    if cid not in bdf.coords:
        raise MissingReferenceError(card_message(f"coordinate system {cid} is not defined.",
                                                 card=card, card_id=card_id, filename=filename,
                                                 fix=f"add a CORD2R {cid} or use 0 (basic)."))
    coord = bdf.coords[cid]
    if coord.type not in ("CORD2R", "CORD1R"):
        raise UnsupportedCardError(card_message(
            f"coordinate system {cid} is a {coord.type}; only rectangular systems are allowed "
            "here.",
            card=card, card_id=card_id, filename=filename, fix=f"make {cid} a CORD2R."))
    return Frame(cid, np.asarray(coord.origin, dtype=float), np.asarray(coord.beta(), dtype=float),
                 filename)


def _check_cards(bdf, filename: str) -> None:
    bad = {name: n for name, n in bdf.card_count.items() if name in UNSUPPORTED_AERO_CARDS}
    for eid, caero in bdf.caeros.items():
        if caero.type != "CAERO1":
            bad.setdefault(caero.type, 0)
    for pid, paero in bdf.paeros.items():
        if paero.type == "PAERO1" and [b for b in (paero.caero_body_ids or []) if b]:
            bad[f"PAERO1 {pid} with body ids {list(paero.caero_body_ids)}"] = 1
    if bad:
        raise UnsupportedCardError(card_message(
            f"aerodynamic cards not modelled: {', '.join(sorted(bad))} (bodies, other panel types, "
            "other splines and control-surface cards are not supported).", filename=filename,
            fix="model lifting surfaces with CAERO1/PAERO1 (no bodies) and splines with "
                "SPLINE1/SPLINE2, or remove these cards."))


def _fractions(bdf, n, aefact_id, what: str, eid: int, filename: str) -> np.ndarray:
    if aefact_id in (None, 0):
        if not n or n < 1:
            raise InputError(card_message(f"N{what}={n}: needs >= 1 division or an AEFACT in "
                                          f"L{what}.", card="CAERO1", card_id=eid,
                                          filename=filename,
                                          fix=f"set N{what} or L{what}."))
        if n > MAX_BOXES:
            raise InputError(card_message(f"N{what}={n} divisions exceed the {MAX_BOXES} boxes a "
                                          "deck may have.", card="CAERO1", card_id=eid,
                                          filename=filename, fix=f"correct N{what}."))
        return np.linspace(0.0, 1.0, int(n) + 1)
    if aefact_id not in bdf.aefacts:
        raise MissingReferenceError(card_message(f"L{what}={aefact_id} refers to a missing AEFACT.",
                                                 card="CAERO1", card_id=eid, filename=filename,
                                                 fix=f"add AEFACT {aefact_id} with the division "
                                                     "fractions 0.0 ... 1.0."))
    return np.asarray(bdf.aefacts[aefact_id].fractions, dtype=float)


def _panels(bdf, aero_frame: Frame, filename: str) -> list:
    panels = []
    for eid in sorted(bdf.caeros):
        c = bdf.caeros[eid]
        if c.pid not in bdf.paeros:
            raise MissingReferenceError(card_message(f"PID={c.pid} refers to a missing PAERO1.",
                                                     card="CAERO1", card_id=eid, filename=filename,
                                                     fix=f"add 'PAERO1,{c.pid}'."))
        cp = _frame(bdf, c.cp, "CAERO1", eid, filename)
        p1 = aero_frame.from_basic(cp.to_basic(np.asarray(c.p1, dtype=float)))
        p4 = aero_frame.from_basic(cp.to_basic(np.asarray(c.p4, dtype=float)))
        panels.append(Caero1Panel(
            eid=eid, pid=c.pid, cp=c.cp or 0, igid=c.igroup or 0, p1=p1, x12=float(c.x12), p4=p4,
            x43=float(c.x43),
            span_fractions=_fractions(bdf, c.nspan, c.lspan, "SPAN", eid, filename),
            chord_fractions=_fractions(bdf, c.nchord, c.lchord, "CHORD", eid, filename),
            filename=filename))
    return panels


def _splines(bdf, panels: list, filename: str) -> list:
    ranges = {p.eid: (int(p.box_ids[0]), int(p.box_ids[-1])) for p in panels}
    out = []
    for eid in sorted(bdf.splines):
        s = bdf.splines[eid]
        card = s.type
        if s.caero not in ranges:
            raise MissingReferenceError(card_message(f"CAERO={s.caero} is not a CAERO1 of the "
                                                     "deck.", card=card, card_id=eid,
                                                     filename=filename,
                                                     fix=f"use one of {sorted(ranges)}."))
        lo, hi = ranges[s.caero]
        if not (lo <= s.box1 <= s.box2 <= hi):
            raise InputError(card_message(
                f"box range {s.box1}..{s.box2} lies outside CAERO1 {s.caero}'s boxes {lo}..{hi}.",
                card=card, card_id=eid, filename=filename,
                fix=f"set BOX1/BOX2 within {lo}..{hi}."))
        if s.setg not in bdf.sets:
            raise MissingReferenceError(card_message(f"SETG={s.setg} refers to a missing SET1.",
                                                     card=card, card_id=eid, filename=filename,
                                                     fix=f"add 'SET1,{s.setg},<grid ids>'."))
        gids = np.array(sorted(set(int(g) for g in bdf.sets[s.setg].ids)), dtype=int)
        missing = [g for g in gids if g not in bdf.nodes]
        if missing:
            raise MissingReferenceError(card_message(
                f"SET1 {s.setg} lists grids {missing[:10]} that are not defined.", card=card,
                card_id=eid, filename=filename,
                fix="define those GRIDs or remove them from the SET1."))
        xyz = np.array([bdf.nodes[g].get_position() for g in gids], dtype=float)
        common = dict(eid=eid, caero=s.caero, box1=s.box1, box2=s.box2, setg=s.setg, grid_ids=gids,
                      grid_xyz=xyz, dz=float(s.dz or 0.0), usage=(s.usage or "BOTH").upper(),
                      filename=filename)
        if card == "SPLINE1":
            method = (s.method or "IPS").upper()
            if method != "IPS":
                raise UnsupportedCardError(card_message(
                    f"METH={method} not supported (only the infinite-plate spline IPS).", card=card,
                    card_id=eid, filename=filename, fix="use METH=IPS (or blank)."))
            out.append(Spline(kind="IPS", **common))
        else:
            dtor = 1.0 if s.dtor in (None, "") else float(s.dtor)
            out.append(Spline(kind="BEAM", dtor=dtor,
                              dthx=float(0.0 if s.dthx is None else s.dthx),
                              dthy=float(0.0 if s.dthy is None else s.dthy),
                              frame=_frame(bdf, s.cid, card, eid, filename), **common))
    covered = {}
    for sp in out:
        for usage in ("DISP", "FORCE"):
            if sp.usage not in ("BOTH", usage):
                continue
            for box in range(sp.box1, sp.box2 + 1):
                if (box, usage) in covered:
                    raise InputError(card_message(
                        f"box {box} is already interpolated by {covered[(box, usage)]} "
                        f"(usage {usage}).", card=sp.card, card_id=sp.eid, filename=filename,
                        fix="make the BOX1..BOX2 ranges of the splines disjoint."))
                covered[(box, usage)] = f"{sp.card} {sp.eid}"
    return out


def _mach_k(bdf, filename: str) -> np.ndarray:
    pairs = []
    for card in bdf.mkaeros:
        machs = np.asarray(card.machs, dtype=float)
        ks = np.asarray(card.reduced_freqs, dtype=float)
        if card.type == "MKAERO1":
            pairs += [(m, k) for m in machs for k in ks]
        else:
            pairs += list(zip(machs, ks))
    mk = np.array(pairs, dtype=float).reshape(-1, 2)
    if not np.all(np.isfinite(mk)) or np.any(mk < 0) or np.any(mk[:, 0] >= 1.0):
        raise InputError(card_message(
            "a Mach number or reduced frequency is negative or not finite, or a Mach number is "
            ">= 1 (the doublet-lattice method is subsonic).", card="MKAERO1", filename=filename,
            fix="use finite Mach numbers 0 <= M < 1 and reduced frequencies k >= 0."))
    return mk


def read_aero_model(path_or_bdf) -> AeroModel:
    """Read the aerodynamic model of a Nastran deck.

    Parameters
    ----------
    path_or_bdf : str, Path or pyNastran BDF
        The deck (INCLUDEs resolved), or an already read pyNastran ``BDF`` whose nodes and
        coordinate systems are cross-referenced.

    Returns
    -------
    AeroModel
        Reference values, CAERO1 panels and their boxes (ACSID frame), splines with their structural
        grids (basic positions) and the MKAERO Mach-k pairs.

    Raises
    ------
    UnsupportedCardError
        Bodies (PAERO1 body ids), CAERO2-5, SPLINE3+, control-surface cards, SYMXY != 0.
    MissingReferenceError
        A PAERO1, AEFACT, SET1, GRID or coordinate system referenced but not defined.
    InputError
        No AERO/AEROS, no CAERO1, spline box ranges outside their CAERO1 or overlapping.
    """
    if isinstance(path_or_bdf, (str, Path)):
        filename = str(path_or_bdf)
        bdf = read_pynastran(path_or_bdf)
    else:
        bdf = path_or_bdf
        filename = str(getattr(bdf, "bdf_filename", "") or "<BDF object>")
    _check_cards(bdf, filename)
    aero, aeros = bdf.aero, bdf.aeros
    if aero is None and aeros is None:
        raise InputError(card_message("no AERO or AEROS card.", filename=filename,
                                      fix="add 'AERO,ACSID,VELOCITY,REFC,RHOREF,SYMXZ,SYMXY'."))
    if aero is not None:
        acsid, refc, rhoref = aero.acsid or 0, float(aero.cref), float(aero.rho_ref)
        velocity = None if aero.velocity is None else float(aero.velocity)
        symxz, symxy = int(aero.sym_xz or 0), int(aero.sym_xy or 0)
    else:
        acsid, refc, rhoref, velocity = aeros.acsid or 0, float(aeros.cref), 1.0, None
        symxz, symxy = int(aeros.sym_xz or 0), int(aeros.sym_xy or 0)
    if symxy != 0:
        raise UnsupportedCardError(card_message(
            f"SYMXY={symxy} (ground effect / xy-plane image) is not modelled.", card="AERO",
            filename=filename, fix="set SYMXY=0."))
    aero_frame = _frame(bdf, acsid, "AERO", None, filename)
    panels = _panels(bdf, aero_frame, filename)
    if not panels:
        raise InputError(card_message("no CAERO1 panels.", filename=filename,
                                      fix="add CAERO1/PAERO1 cards for the lifting surfaces."))
    nbox = sum(p.nspan * p.nchord for p in panels)
    if nbox > MAX_BOXES:
        raise InputError(card_message(
            f"the CAERO1 panels divide into {nbox} boxes, more than {MAX_BOXES} (the "
            f"doublet-lattice AIC would take {16e-9 * nbox ** 2:.0f} GB).", filename=filename,
            fix="correct NSPAN/NCHORD or the AEFACT division lists."))
    meshes = [caero1_boxes(p.eid, p.p1, p.x12, p.p4, p.x43, p.span_fractions, p.chord_fractions,
                           first_box_id=p.eid, filename=filename) for p in panels]
    return AeroModel(filename=filename, aero_frame=aero_frame, refc=refc, rhoref=rhoref,
                     velocity=velocity, symxz=symxz, symxy=symxy, panels=tuple(panels),
                     splines=tuple(_splines(bdf, panels, filename)), mesh=concat(meshes),
                     mach_k=_mach_k(bdf, filename))
