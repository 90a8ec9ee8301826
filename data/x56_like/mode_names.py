"""Names of the X-56A-class model's modes from their shapes, in the reference paper's vocabulary.

A mode is named from three things read off its shape (``shape(mode, dof)`` of the modes Dataset,
grid translations and rotations in the basic frame):

1. symmetry about the centre line (the xz plane): with every grid paired with its mirror image
   (x, -y, z), a symmetric shape has T1, T3, R2 equal and T2, R1, R3 opposite at the two grids.
   ``s = sum(phi_g . S phi_g') / sum |phi_g|^2`` with S = diag(1, -1, 1, -1, 1, -1) is +1 for a
   symmetric and -1 for an antisymmetric shape; prefix ``S`` or ``A``.
2. the component of the structure holding most of the mode's kinetic energy, with the energy of
   every CONM2 of the generator: m |u + theta x r|^2 (r the CONM2 offset) plus its rotary inertia
   (make_model.COMPONENTS: centre body, boom, wing, winglet, engine, nose gear, main gear). An
   appendage (engine, gear, boom) counts only its motion relative to the rigid motion of the grid
   it hangs from; the winglets move with the wing tip, and a mode is a winglet mode only when they
   carry more than ``WINGLET_SHARE`` of the energy (wing bending swings them too).
3. the dominant motion of that component: for the wings the energy of vertical bending (the
   elastic-axis translation T3), of torsion (the chordwise rotation about the elastic axis) and of
   in-plane (fore-aft) motion; for the gear, engines and boom the dominant translation of their
   masses (T1 fore-aft, T2 lateral, T3 vertical).

Names (Table 1 of the paper and its nomenclature): SW1B / AW1B (wing bending, numbered in
frequency order per kind), SW1T / AW1T (torsion), SW1FA / AW1FA (wing fore-aft), SWL / AWL
(winglet), SEL / AEL (engine lateral), SEP / AEP (engine pitch / vertical), SMLGL / AMLGL and
SMLGFA / AMLGFA (main gear lateral, fore-aft), NLGL / NLGFA (nose gear), BoomH / BoomV (nose boom
horizontal / vertical), CB (centre body); ``RB`` below ``rigid_hz``. A repeated name gets a
number (AMLGL2).
"""
from __future__ import annotations

import math
from collections import Counter

import numpy as np
import xarray as xr

import make_model as mm

MIRROR = np.array([1.0, -1.0, 1.0, -1.0, 1.0, -1.0])
#: A winglet mode: the winglets (moving with the wing tip) carry more than this share of the energy.
WINGLET_SHARE = 0.55


def _grid_shapes(modes: xr.Dataset) -> tuple[np.ndarray, dict]:
    """(nmode, ngrid, 6) shapes and grid id -> index."""
    grid = modes["grid"].values.astype(int)
    comp = modes["component"].values.astype(int)
    ids = np.unique(grid)
    index = {int(g): i for i, g in enumerate(ids)}
    out = np.zeros((modes.sizes["mode"], ids.size, 6))
    out[:, [index[int(g)] for g in grid], comp - 1] = modes["shape"].values
    return out, index


def _mirror_pairs(xyz: dict, index: dict) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs (g, g') of grids mirrored about y = 0 (centre-line grids pair with themselves)."""
    key = {(round(x, 3), round(y, 3), round(z, 3)): gid for gid, (x, y, z) in xyz.items()}
    a, b = [], []
    for gid, (x, y, z) in xyz.items():
        other = key.get((round(x, 3), round(-y, 3), round(z, 3)))
        if other is not None and gid in index and other in index:
            a.append(index[gid])
            b.append(index[other])
    return np.array(a), np.array(b)


def _attachment(grid: int) -> int | None:
    """Grid an appendage hangs from (its motion relative to that grid's rigid motion is its own)."""
    name = mm.component_of(grid)
    if name == "engine":
        return 1006
    if name == "nose gear":
        return 1002
    if name == "main gear":
        return 2101 if grid >= 6200 else 2001
    if name == "boom":
        return 1001
    return None


def _energies(phi: np.ndarray, index: dict, params, xyz: dict, configuration: str) -> dict:
    """Kinetic energy per component and motion: columns T1, T2, T3 of the masses and rotation
    (wing: rotation about the elastic axis). Appendages (winglet, engine, gear, boom) count only
    their motion relative to the rigid motion of the grid they hang from."""
    out: dict = {}
    for m in mm.mass_items(params, configuration):
        comp = mm.component_of(m.grid)
        comp = "wing" if comp == "carry-through" else comp
        u = phi[index[m.grid]].copy()
        r = np.asarray(m.offset, dtype=float)
        root = _attachment(m.grid)
        if root is not None:
            ur = phi[index[root]]
            arm = np.asarray(xyz[m.grid]) - np.asarray(xyz[root])
            u[:3] -= ur[:3] + np.cross(ur[3:], arm)
            u[3:] -= ur[3:]
        v = u[:3] + np.cross(u[3:], r)
        e = out.setdefault(comp, np.zeros(4))
        if comp == "wing":
            y = abs(xyz[m.grid][1])
            sweep = math.atan2(mm.EA * (mm.C_TIP - mm.C_ROOT), mm.Y_TIP - mm.Y_ROOT) + mm.SWEEP_LE
            axis = np.array([math.sin(sweep), math.copysign(math.cos(sweep), xyz[m.grid][1] or 1.0),
                             0.0]) if y >= mm.Y_ROOT else np.array([0.0, 1.0, 0.0])
            twist = float(u[3:] @ axis)
            chordwise = m.inertia[1] + m.weight * float(r @ r)
            e += m.weight * np.array([v[0] ** 2 + v[1] ** 2, 0.0, u[2] ** 2, 0.0]) \
                + np.array([0.0, 0.0, 0.0, chordwise * twist ** 2])
        else:
            e += m.weight * np.array([v[0] ** 2, v[1] ** 2, v[2] ** 2, 0.0]) \
                + np.array([0.0, 0.0, 0.0, float(np.dot(m.inertia, u[3:] ** 2))])
    return out


def _kind(component: str, e: np.ndarray) -> str:
    t1, t2, t3, rot = e
    if component == "wing":
        return ("FA", "B", "T")[int(np.argmax([t1, t3, rot]))]
    if component == "winglet":
        return "WL"
    if component == "engine":
        return "EL" if t2 >= max(t1, t3) else "EP"
    if component in ("main gear", "nose gear"):
        return "L" if t2 >= max(t1, t3) else ("FA" if t1 >= t3 else "V")
    if component == "boom":
        return "H" if t2 >= t3 else "V"
    return "B" if t3 >= max(t1, t2) else ("L" if t2 >= t1 else "FA")


def classify_modes(modes: xr.Dataset, configuration: str, params=mm.ANALYSIS,
                   rigid_hz: float = 0.05) -> list[dict]:
    """Name every mode of a modes Dataset of the generator's model.

    Parameters
    ----------
    modes : xarray.Dataset
        ``frequency(mode)`` [Hz], ``shape(mode, dof)`` with ``grid(dof)``, ``component(dof)``.
    configuration : {"efew", "fffw"}
        Selects the tank masses used for the kinetic energies.
    params : make_model.X56Parameters
    rigid_hz : float
        Modes below this frequency are rigid-body modes (``RB``).

    Returns
    -------
    list of dict, one per mode (in order): ``mode``, ``frequency`` [Hz], ``name``, ``symmetry``
    (+1 symmetric .. -1 antisymmetric), ``component``, ``energy_share`` (of that component).
    """
    shapes, index = _grid_shapes(modes)
    xyz = mm._grids(params)
    a, b = _mirror_pairs(xyz, index)
    counts: Counter = Counter()
    out = []
    for j, f in enumerate(np.asarray(modes["frequency"].values, dtype=float)):
        phi = shapes[j]
        sym = float(np.sum(phi[a] * phi[b] * MIRROR) / max(np.sum(phi[a] ** 2), 1e-300))
        energy = _energies(phi, index, params, xyz, configuration)
        total = sum(float(e.sum()) for e in energy.values())
        ranked = sorted(energy, key=lambda c: -float(energy[c].sum()))
        component = ranked[0]
        if component == "winglet" and float(energy[component].sum()) < WINGLET_SHARE * total:
            component = ranked[1]
        share = float(energy[component].sum()) / total if total > 0 else 0.0
        if f < rigid_hz:
            name = "RB"
        else:
            kind = _kind(component, energy[component])
            s = "S" if sym >= 0 else "A"
            if component == "wing":
                base = f"{s}W{{n}}{kind}"
            elif component == "main gear":
                base = f"{s}MLG{kind}"
            elif component == "nose gear":
                base = f"NLG{kind}"
            elif component == "boom":
                base = f"Boom{kind}"
            elif component == "winglet":
                base = f"{s}WL"
            elif component == "engine":
                base = f"{s}{kind}"
            else:
                base = f"{s}CB{kind}"
            counts[base] += 1
            n = counts[base]
            name = base.format(n=n) if "{n}" in base else (base if n == 1 else f"{base}{n}")
        out.append({"mode": int(modes["mode"].values[j]), "frequency": float(f), "name": name,
                    "symmetry": sym, "component": component, "energy_share": share})
    return out


def mode_table_markdown(tables: dict[str, list[dict]]) -> str:
    """Markdown table of both configurations' modes side by side (mode, name, Hz, component)."""
    confs = list(tables)
    n = max(len(t) for t in tables.values())
    head = "| mode | " + " | ".join(f"{c.upper()} name | {c.upper()} Hz | {c.upper()} component"
                                    for c in confs) + " |"
    rule = "|---:|" + "|".join(":---|---:|:---" for _ in confs) + "|"
    rows = []
    for i in range(n):
        cells = []
        for c in confs:
            r = tables[c][i] if i < len(tables[c]) else None
            if r is None:
                cells += ["", "", ""]
            elif r["name"] == "RB":              # a rigid-body mode's shape is any basis vector
                cells += ["RB", "0", "rigid body"]
            else:
                cells += [r["name"], f"{r['frequency']:.3f}",
                          f"{r['component']} ({100 * r['energy_share']:.0f} %)"]
        rows.append(f"| {i + 1} | " + " | ".join(cells) + " |")
    return "\n".join([head, rule, *rows]) + "\n"
