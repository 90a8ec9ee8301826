"""Flutter summary: critical roots, their type, and the margin against a flight envelope.

The clearance requirement is the usual 15% margin: no flutter within 1.15 x the envelope speed
(14 CFR 25.629(b)(1): "1.15 V_D"; MIL-A-8870C sec. 3.1.1 "1.15 V_L" in equivalent airspeed).
The margin of a flutter point is ``V_f / (1.15 V_env(M)) - 1`` (>= 0: cleared), with V_env
interpolated in Mach along the stated envelope.

Type of a root: ``divergence`` for a zero-frequency crossing; ``body-freedom`` when the rigid-body
modes take at least ``bff_share`` of the flutter mode's participation (flutter.participation);
otherwise the two most participating flexible modes name it, e.g. ``"SW1B-SW1T"`` with mode names,
and ``bending-torsion`` is added when the names say so (B and T suffixes, as in the paper's SW1B /
SW1T).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from flutter.participation import crossing_participation
from structures.common.errors import InputError

MARGIN_FACTOR = 1.15


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


def classify(part: xr.Dataset, index: int, names: dict | None = None, bff_share: float = 30.0) -> str:
    """Type of flutter mode ``index`` of a participation Dataset (see module docstring)."""
    P = part.participation.values[index]
    rigid = part.rigid.values
    if P[rigid].sum() >= bff_share:
        return "body-freedom"
    flex = np.flatnonzero(~rigid)
    top = flex[np.argsort(P[flex])[::-1][:2]]
    modes = part["mode"].values
    labels = [str((names or {}).get(int(modes[j]), f"mode {int(modes[j])}")) for j in top]
    text = "-".join(labels)
    kinds = {lab[-1] for lab in labels if lab[-1:] in ("B", "T")}
    if kinds == {"B", "T"}:
        text += " (bending-torsion)"
    return text


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
        Ordered by speed: ``root``, ``kind``, ``type``, ``velocity``, ``frequency``, ``mach``,
        ``density``, ``margin`` (None without envelope).
    """
    part = crossing_participation(ds, mass, omega, rigid_hz)
    out = []
    for i in range(ds.sizes.get("crossing", 0)):
        kind = str(ds.crossing_kind.values[i])
        V = float(ds.crossing_velocity[i])
        entry = {"root": int(ds.crossing_root[i]), "kind": kind, "velocity": V,
                 "frequency": float(ds.crossing_frequency[i]), "mach": float(ds.crossing_mach[i]),
                 "density": float(ds.crossing_density[i]), "type": "divergence"}
        if kind == "flutter":
            j = int(np.flatnonzero(np.isclose(part.velocity.values, V))[0])
            entry["type"] = classify(part, j, names)
        entry["margin"] = (None if envelope is None
                           else V / (MARGIN_FACTOR * float(envelope.at(entry["mach"]))) - 1.0)
        out.append(entry)
    return sorted(out, key=lambda e: e["velocity"])
