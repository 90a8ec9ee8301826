"""Flutter summary: critical roots, their type, and the margin against a flight envelope.

The clearance requirement is the usual 15% margin: no flutter within 1.15 x the envelope speed
(14 CFR 25.629(b)(1): "1.15 V_D"; MIL-A-8870C sec. 3.1.1 "1.15 V_L" in equivalent airspeed).
The margin of a flutter point is ``V_f / (1.15 V_env(M)) - 1`` (>= 0: cleared), with V_env
interpolated in Mach along the stated envelope.

Kind of a crossing (summary.json ``kind``): ``divergence`` for a zero-frequency crossing;
``body_freedom_flutter`` for a flutter crossing whose rigid-body modes take at least
:data:`BFF_SHARE` of its participation (flutter.participation); else ``flutter``
(:func:`crossing_kinds`; :func:`flutter.results.is_flutter` is true for both flutter kinds).

Type of a root: ``divergence``; otherwise the two most participating flexible modes name it, e.g.
``"SW1B-SW1T"`` with mode names, and ``bending-torsion`` is added when the names say so (B and T
suffixes, as in the paper's SW1B / SW1T); a body-freedom flutter is ``"body-freedom: R-F"`` with R
the most participating rigid-body mode (its name, its ``rigid_motion`` such as ``pitch``, else
``rigid mode n``) and F the most participating flexible mode, e.g. ``"body-freedom: pitch-SW1B"``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from flutter.participation import crossing_participation, participation_factors
from structures.common.errors import InputError

MARGIN_FACTOR = 1.15
#: Share [%] of a flutter mode's participation (flutter.participation, kinetic energy, sums to
#: 100) taken by the rigid-body modes from which a flutter crossing is body-freedom flutter: the
#: rigid-body motion carries most of the flutter motion's kinetic energy. In a body-freedom
#: flutter the short period is one of the coalescing modes (Weisshaar & Zeiler, "Dynamic
#: stability of flexible forward swept wing aircraft", J. Aircraft 20(12), 1983; Pak & Truong
#: Fig. 14: "huge center body longitudinal motions"); a classical flutter of a free aircraft
#: moves its rigid-body modes much less. Measured (p-k, our modes and GAFs): classical flutter
#: 9.2 % (bah_plane wing bending-torsion, 394 m/s), 15.6-25.6 % (X-56A-class wing flutters, both
#: configurations, 4 Mach), 27.0 and 30.3 % (data/bff_wing's 11 and 21 Hz wing flutters);
#: symmetric body-freedom flutter (the short period with the first bending) 83-95 % (X-56A-class
#: SBFF, both configurations) and 83 % (bff_wing SBFF). 50 % lies 1.65 x above the largest
#: classical share and 1.66 x below the smallest SBFF one (30 %, the earlier value, named
#: bff_wing's 30.3 % wing flutter body-freedom). The X-56A-class EFEW 7 Hz antisymmetric flutter,
#: in which the rigid roll takes 74-82 %, then falls on the body-freedom side too (reported
#: "body-freedom: roll-AW1T").
BFF_SHARE = 50.0


@dataclass(frozen=True)
class Envelope:
    """Flight envelope as maximum speed versus Mach (model velocity units, or KEAS if stated).

    Parameters
    ----------
    mach : tuple of float
        Increasing Mach numbers.
    velocity : tuple of float
        Envelope speed (V_D / V_L) at each Mach.
    units : str
        Label of the velocity units.
    """

    mach: tuple
    velocity: tuple
    units: str = "model"

    def __post_init__(self):
        m = tuple(float(x) for x in self.mach)
        v = tuple(float(x) for x in self.velocity)
        if len(m) != len(v) or len(m) == 0 or np.any(np.diff(m) <= 0) or min(v) <= 0:
            raise InputError("Envelope: give increasing Mach numbers and one positive speed per Mach. "
                             "Fix: check the envelope table.")
        object.__setattr__(self, "mach", m)
        object.__setattr__(self, "velocity", v)

    def at(self, mach) -> np.ndarray:
        """Envelope speed at ``mach`` (linear; held at the ends)."""
        return np.interp(mach, self.mach, self.velocity)


def classify(part: xr.Dataset, index: int, names: dict | None = None,
             bff_share: float = BFF_SHARE) -> str:
    """Type of flutter mode ``index`` of a participation Dataset (see module docstring).

    Parameters
    ----------
    part : xarray.Dataset
        ``participation(flutter_mode | flutter_point, mode)`` [%] with coordinate ``rigid(mode)``
        and optionally ``rigid_motion(mode)`` (:func:`flutter.participation.crossing_participation`,
        participation.nc).
    index : int
        Position of the flutter mode.
    names : dict, optional
        Mode id -> name (e.g. {7: "SW1B"}).
    bff_share : float
        Rigid-body share [%] from which the type is body-freedom.

    Returns
    -------
    str
    """
    P = part.participation.values[index]
    rigid = part.rigid.values.astype(bool)
    modes = part["mode"].values
    motion = (part["rigid_motion"].values.astype(str) if "rigid_motion" in part.coords
              else np.full(modes.size, ""))

    def name(j):
        default = motion[j] or f"{'rigid mode' if rigid[j] else 'mode'} {int(modes[j])}"
        return str((names or {}).get(int(modes[j]), default))

    flex = np.flatnonzero(~rigid)
    if P[rigid].sum() >= bff_share:
        top_rigid = np.flatnonzero(rigid)[np.argmax(P[rigid])]
        return "body-freedom: " + "-".join(
            [name(top_rigid)] + [name(j) for j in flex[np.argsort(P[flex])[::-1][:1]]])
    labels = [name(j) for j in flex[np.argsort(P[flex])[::-1][:2]]]
    text = "-".join(labels)
    kinds = {lab[-1] for lab in labels if lab[-1:] in ("B", "T")}
    if kinds == {"B", "T"}:
        text += " (bending-torsion)"
    return text


def crossing_kinds(ds: xr.Dataset, mass: np.ndarray, omega: np.ndarray, rigid_hz: float = 0.05,
                   bff_share: float = BFF_SHARE) -> np.ndarray:
    """Kind of every crossing of a sweep: ``divergence``, ``flutter`` or ``body_freedom_flutter``.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep with crossings (``crossing_kind``, ``crossing_eigenvector``).
    mass : ndarray, shape (n, n)
        Generalized mass.
    omega : ndarray, shape (n,)
        In-vacuo circular frequencies [rad/s] (rigid-body modes below ``rigid_hz``).
    rigid_hz : float
    bff_share : float
        Rigid-body share [%] of the participation from which flutter is body-freedom flutter.

    Returns
    -------
    ndarray of str (object), shape (ncrossing,)
    """
    kinds = np.array([str(k) for k in ds["crossing_kind"].values], dtype=object)
    flutter = np.flatnonzero(kinds != "divergence")
    if flutter.size:
        rigid = np.asarray(omega, dtype=float) / (2 * np.pi) < rigid_hz
        P = participation_factors(ds["crossing_eigenvector"].values[flutter], mass)
        kinds[flutter] = np.where(P[:, rigid].sum(axis=1) >= bff_share, "body_freedom_flutter",
                                  "flutter")
    return kinds


def flutter_summary(ds: xr.Dataset, mass: np.ndarray, omega: np.ndarray,
                    envelope: Envelope | None = None, names: dict | None = None,
                    rigid_hz: float = 0.05) -> list[dict]:
    """Critical roots of one sweep: speed, frequency, type and margin.

    Parameters
    ----------
    ds : xarray.Dataset
        A :func:`flutter.pk.pk_solve` result.
    mass : ndarray, shape (n, n)
        Generalized mass.
    omega : ndarray, shape (n,)
        In-vacuo circular frequencies (rigid-body modes below ``rigid_hz``).
    envelope : Envelope, optional
        Gives ``margin`` = V / (1.15 V_env(M)) - 1.
    names : dict, optional
        Mode id -> name (e.g. {7: "SW1B"}).

    Returns
    -------
    list of dict
        Ordered by speed: ``root``, ``kind`` (:func:`crossing_kinds`), ``type``, ``velocity``,
        ``frequency``, ``mach``, ``density``, ``margin`` (None without envelope).
    """
    part = crossing_participation(ds, mass, omega, rigid_hz)
    kinds = crossing_kinds(ds, mass, omega, rigid_hz) if ds.sizes.get("crossing", 0) else []
    out = []
    for i in range(ds.sizes.get("crossing", 0)):
        kind = str(kinds[i])
        V = float(ds.crossing_velocity[i])
        entry = {"root": int(ds.crossing_root[i]), "kind": kind, "velocity": V,
                 "frequency": float(ds.crossing_frequency[i]), "mach": float(ds.crossing_mach[i]),
                 "density": float(ds.crossing_density[i]), "type": "divergence"}
        if kind != "divergence":
            j = int(np.flatnonzero(np.isclose(part.velocity.values, V))[0])
            entry["type"] = classify(part, j, names)
        entry["margin"] = (None if envelope is None
                           else V / (MARGIN_FACTOR * float(envelope.at(entry["mach"]))) - 1.0)
        out.append(entry)
    return sorted(out, key=lambda e: e["velocity"])
