"""Aerodynamic box geometry of CAERO1 lifting-surface panels.

A CAERO1 panel is a flat trapezoid whose two chords run along the basic x axis (the free-stream
direction): the leading-edge points ``p1`` (root) and ``p4`` (tip) with chords ``x12`` and ``x43``.
It is divided into boxes by spanwise and chordwise fractions (uniform from NSPAN/NCHORD or uneven
from AEFACT lists). Each box carries, as in the doublet-lattice method (Albano & Rodden 1969,
AIAA J. 7(2), 279-285, sec. II), a doublet (bound-vortex) line on its 1/4-chord line and a
collocation point at 3/4 of its chord, mid-span.

Orientation rule (Nastran's CAERO1 element frame): x is the stream direction (basic +x),
y_e is the unit vector from the ``p1`` side to the ``p4`` side projected on the basic y-z plane,
and the box normal is ``n = x x y_e``. A right wing defined root to tip (p4 at +y) therefore has
its normal along +z; a panel defined right-to-left (p4 at more negative y than p1) has its normal
along -z, and a vertical fin defined bottom to top has its normal along -y. Pressures
(Delta Cp = (p_lower - p_upper)/q) are positive along this normal. Corner 1 is always the
leading-edge corner on the ``p1`` side ("inboard" in the sense of the card), 2 the leading-edge
corner on the ``p4`` side, 3 the trailing-edge corner on the ``p4`` side and 4 the trailing-edge
corner on the ``p1`` side.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from structures.common.errors import InputError, card_message

__all__ = ["BoxMesh", "caero1_boxes", "concat", "mirror_xz"]

_FIELDS = ("corners", "doublet_in", "doublet_out", "collocation", "normal", "area", "chord",
           "span", "panel_id", "box_id")


def _readonly(a: np.ndarray, dtype) -> np.ndarray:
    out = np.array(a, dtype=dtype, copy=True)
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class BoxMesh:
    """Stacked geometry of ``n`` aerodynamic boxes (basic frame, the deck's length unit).

    Attributes
    ----------
    corners : (n, 4, 3) float
        Corners 1..4: leading edge p1 side, leading edge p4 side, trailing edge p4 side,
        trailing edge p1 side.
    doublet_in, doublet_out : (n, 3) float
        End points of the 1/4-chord doublet line on the p1 side and on the p4 side.
    collocation : (n, 3) float
        Collocation point at 3/4 chord, mid-span.
    normal : (n, 3) float
        Unit normal ``x x y_e`` (no x component; see the module docstring for the rule).
    area : (n,) float
        Box area, ``chord * span``.
    chord : (n,) float
        Mean streamwise box chord (the Delta x of the doublet-lattice method).
    span : (n,) float
        Length of the doublet line projected on the y-z plane (twice the semi-width e).
    panel_id : (n,) int
        EID of the CAERO1 the box belongs to.
    box_id : (n,) int
        Nastran box number: EID (or LSPAN-style first id) + running index, chordwise fastest.
    """

    corners: np.ndarray
    doublet_in: np.ndarray
    doublet_out: np.ndarray
    collocation: np.ndarray
    normal: np.ndarray
    area: np.ndarray
    chord: np.ndarray
    span: np.ndarray
    panel_id: np.ndarray
    box_id: np.ndarray
    n: int = field(init=False)

    def __post_init__(self) -> None:
        corners = np.asarray(self.corners, dtype=float)
        n = corners.shape[0] if corners.ndim == 3 else -1
        shapes = {"corners": (n, 4, 3), "doublet_in": (n, 3), "doublet_out": (n, 3),
                  "collocation": (n, 3), "normal": (n, 3), "area": (n,), "chord": (n,),
                  "span": (n,), "panel_id": (n,), "box_id": (n,)}
        for name in _FIELDS:
            value = np.asarray(getattr(self, name))
            if n < 0 or value.shape != shapes[name]:
                raise InputError(card_message(
                    f"BoxMesh field {name!r} has shape {value.shape}, expected {shapes[name]} "
                    f"(n = number of boxes).", fix="build meshes with caero1_boxes/concat."))
            dtype = np.int64 if name in ("panel_id", "box_id") else float
            if dtype is float and not np.all(np.isfinite(value)):
                raise InputError(card_message(f"BoxMesh field {name!r} holds non-finite values.",
                                              fix="check the CAERO1 points and chords."))
            object.__setattr__(self, name, _readonly(value, dtype))
        if np.unique(self.box_id).size != n:
            dup = self.box_id[np.argsort(self.box_id)]
            dup = np.unique(dup[1:][dup[1:] == dup[:-1]])
            raise InputError(card_message(
                f"duplicate aerodynamic box ids {dup[:10].tolist()}.", card="CAERO1",
                fix="give the CAERO1 panels EIDs whose box ranges do not overlap."))
        object.__setattr__(self, "n", n)

    def __len__(self) -> int:
        return self.n


def _check_fractions(values, what: str, panel_id: int, filename: str | None) -> np.ndarray:
    f = np.asarray(values, dtype=float).ravel()
    if f.size < 2 or not np.all(np.isfinite(f)) or abs(f[0]) > 1e-9 or abs(f[-1] - 1.0) > 1e-9 \
            or np.any(np.diff(f) <= 0.0):
        raise InputError(card_message(
            f"{what} fractions {f.tolist()} must increase strictly from 0 to 1.",
            card="CAERO1", card_id=panel_id, filename=filename,
            fix=f"give NSPAN/NCHORD > 0 or an AEFACT list running from 0.0 to 1.0 ({what})."))
    f = f.copy()
    f[0], f[-1] = 0.0, 1.0
    return f


def caero1_boxes(panel_id: int, p1, x12: float, p4, x43: float, span_fractions,
                 chord_fractions, first_box_id: int | None = None,
                 filename: str | None = None) -> BoxMesh:
    """Divide one CAERO1 panel into doublet-lattice boxes.

    Parameters
    ----------
    panel_id : int
        EID of the CAERO1 (used in error messages and ``BoxMesh.panel_id``).
    p1, p4 : (3,) array_like
        Leading-edge points of the p1 side (root) and p4 side (tip), basic frame.
    x12, x43 : float
        Streamwise chords at p1 and p4 (>= 0, not both zero).
    span_fractions : (nspan + 1,) array_like
        Division of the p1-p4 edge, strictly increasing from 0 to 1.
    chord_fractions : (nchord + 1,) array_like
        Division of the chord, strictly increasing from 0 to 1 (same at every span station,
        as on the CAERO1 card).
    first_box_id : int, optional
        Id of the first box; defaults to ``panel_id`` (Nastran numbering).
    filename : str, optional
        The deck the CAERO1 comes from (named in error messages).

    Returns
    -------
    BoxMesh
        ``nspan * nchord`` boxes numbered chordwise fastest.

    Raises
    ------
    InputError
        Non-finite points or chords, zero-area panel (zero span in the y-z plane or zero
        chords), negative chords or bad fractions; the message names the CAERO1 id and the fix.
    """
    pid = int(panel_id)
    p1 = np.asarray(p1, dtype=float).reshape(3)
    p4 = np.asarray(p4, dtype=float).reshape(3)
    x12, x43 = float(x12), float(x43)
    if not (np.all(np.isfinite(p1)) and np.all(np.isfinite(p4)) and np.isfinite(x12 + x43)):
        raise InputError(card_message(
            f"P1={p1.tolist()}, X12={x12}, P4={p4.tolist()}, X43={x43} must be finite.",
            card="CAERO1", card_id=pid, filename=filename,
            fix="give real corner points and chords (and a valid CP coordinate system)."))
    if x12 < 0.0 or x43 < 0.0:
        raise InputError(card_message(f"negative chord (X12={x12}, X43={x43}).", card="CAERO1",
                                      card_id=pid, filename=filename, fix="give chords >= 0."))
    width = float(np.hypot(p4[1] - p1[1], p4[2] - p1[2]))
    scale = max(abs(x12), abs(x43), float(np.linalg.norm(p4 - p1)), 1e-300)
    if width <= 1e-12 * scale or x12 + x43 <= 1e-12 * scale:
        raise InputError(card_message(
            f"zero-area panel (span in the y-z plane {width:g}, chords X12={x12:g}, X43={x43:g}).",
            card="CAERO1", card_id=pid, filename=filename,
            fix="make P1 and P4 differ in y or z and give a non-zero chord; chords run along x."))
    fs = _check_fractions(span_fractions, "span", pid, filename)
    fc = _check_fractions(chord_fractions, "chord", pid, filename)
    ns, nc = fs.size - 1, fc.size - 1

    def point(s, c):
        """Point at span fraction s and chord fraction c (broadcast), basic frame."""
        s = np.asarray(s, dtype=float)[..., None]
        c = np.asarray(c, dtype=float)[..., None]
        chord = x12 + s * (x43 - x12)
        return p1 + s * (p4 - p1) + c * chord * np.array([1.0, 0.0, 0.0])

    si, so = fs[:-1][:, None], fs[1:][:, None]                 # (ns, 1)
    cl, ct = fc[:-1][None, :], fc[1:][None, :]                 # (1, nc)
    sm, cq = 0.5 * (si + so), cl + 0.25 * (ct - cl)
    c34 = cl + 0.75 * (ct - cl)
    corners = np.stack([point(si + 0 * cl, cl + 0 * si), point(so + 0 * cl, cl + 0 * si),
                        point(so + 0 * cl, ct + 0 * si), point(si + 0 * cl, ct + 0 * si)], axis=2)
    d_in = point(si + 0 * cl, cq + 0 * si)
    d_out = point(so + 0 * cl, cq + 0 * si)
    colloc = point(sm + 0 * cl, c34 + 0 * si)
    chord = (ct - cl) * (x12 + sm * (x43 - x12))               # mean box chord (trapezoid)
    span = (so - si) * width + 0 * cl
    ye = np.array([0.0, p4[1] - p1[1], p4[2] - p1[2]]) / width
    normal = np.array([0.0, -ye[2], ye[1]])                    # n = x_hat cross y_e
    n = ns * nc
    first = pid if first_box_id is None else int(first_box_id)
    return BoxMesh(corners=corners.reshape(n, 4, 3), doublet_in=d_in.reshape(n, 3),
                   doublet_out=d_out.reshape(n, 3), collocation=colloc.reshape(n, 3),
                   normal=np.tile(normal, (n, 1)), area=(chord * span).reshape(n),
                   chord=chord.reshape(n), span=span.reshape(n),
                   panel_id=np.full(n, pid), box_id=first + np.arange(n))


def concat(meshes) -> BoxMesh:
    """Stack several meshes (e.g. one per CAERO1) into one, keeping their order.

    Parameters
    ----------
    meshes : sequence of BoxMesh

    Returns
    -------
    BoxMesh
        ``sum(len(m))`` boxes; duplicate box ids raise InputError.
    """
    meshes = list(meshes)
    if not meshes:
        raise InputError(card_message("no aerodynamic panels to stack.",
                                      fix="define at least one CAERO1."))
    return BoxMesh(**{name: np.concatenate([getattr(m, name) for m in meshes], axis=0)
                      for name in _FIELDS})


def mirror_xz(mesh: BoxMesh) -> BoxMesh:
    """Image of a mesh in the plane y = 0, each box in its own (natural) orientation.

    The image of a box keeps its p1 -> p4 direction mirrored, so its natural normal
    ``x x y_e`` is minus the mirror image of the original normal. Box ids are negated so the
    image cannot be confused with real boxes.

    Parameters
    ----------
    mesh : BoxMesh

    Returns
    -------
    BoxMesh
    """
    flip = np.array([1.0, -1.0, 1.0])
    return BoxMesh(corners=mesh.corners * flip, doublet_in=mesh.doublet_in * flip,
                   doublet_out=mesh.doublet_out * flip, collocation=mesh.collocation * flip,
                   normal=-(mesh.normal * flip), area=mesh.area, chord=mesh.chord,
                   span=mesh.span, panel_id=mesh.panel_id, box_id=-mesh.box_id - 1)
