"""Nastran decks for the tuning tests and benchmark, written here with plain text.

``write_aircraft_deck``: a free-free aircraft-like beam/shell model in SI units: a CBAR fuselage
along x; two wings along -+y, each a CBAR spar (inner and outer PBAR) inside a CQUAD4 skin strip
(PSHELL on MAT1 2); a CBAR horizontal tail and fin; two engines (CONM2) hung from the wings on spring
pylons (CELAS1/PELAS 41 translations, CELAS2 rotations, so that one PELAS K is the pylon's design
variable); a payload CONM2 in the fuselage; optional fuel CONM2s along the wing spars (the
"full" configuration). Left and right wings carry their own property ids (linked by tuning).
``write_cantilever_deck``: a clamped CBAR beam whose two first bending modes are a chosen ratio
apart (I2 / I1 sets it), with a tip CONM2.
"""
from __future__ import annotations

import numpy as np

MAT_BAR, MAT_SKIN = 1, 2
PROPS = {  # pid: (A, I1, I2, J)
    1: (6e-3, 6e-5, 8e-5, 1.0e-4),       # fuselage
    11: (3e-3, 2.0e-6, 3e-5, 2.0e-6),    # left inner spar
    12: (3e-3, 2.0e-6, 3e-5, 2.0e-6),    # right inner spar
    13: (2e-3, 0.9e-6, 2e-5, 1.0e-6),    # left outer spar
    14: (2e-3, 0.9e-6, 2e-5, 1.0e-6),    # right outer spar
    31: (1e-3, 2e-6, 2e-5, 2e-6),        # horizontal tail
    32: (1e-3, 3e-6, 1e-5, 3e-6),        # fin
}
PSHELL_T = {21: 1.2e-3, 22: 1.2e-3}      # left / right wing skin
PYLON_K, PYLON_K_ROT = 3e6, 2e5         # engine pylon springs: translations, rotations
ENGINE_MASS = 40.0


def _f(v: float) -> str:
    return f"{float(v):.9e}"


def write_aircraft_deck(path, *, n_span: int = 8, n_chord: int = 2, n_fus: int = 10,
                        fuel: float = 0.0, changes=None, nmodes: int = 30):
    """Write the aircraft deck; ``changes`` maps (card, id, field) to a factor on the start value.

    Parameters
    ----------
    path : Path
    n_span, n_chord : spanwise stations per wing and chordwise skin elements (n_chord even)
    n_fus : fuselage elements
    fuel : total fuel mass [kg] spread over the wing spar grids (0: empty configuration)
    changes : {(card, id, field): factor}
    nmodes : EIGRL ND

    Returns
    -------
    dict with ``path``, ``grids`` {group: grid ids}, ``n_grids``
    """
    changes = dict(changes or {})

    def val(card, pid, fld, v):
        return v * changes.get((card, pid, fld), 1.0)

    lines = ["SOL 103", "CEND", "METHOD = 1", "BEGIN BULK", f"EIGRL,1,,,{nmodes}",
             "PARAM,COUPMASS,1",
             f"MAT1,{MAT_BAR},{_f(val('MAT1', 1, 'E', 70e9))},{_f(27e9)},,2700.",
             f"MAT1,{MAT_SKIN},{_f(val('MAT1', 2, 'E', 70e9))},,0.33,2700."]
    for pid, (a, i1, i2, j) in PROPS.items():
        lines.append(f"PBAR,{pid},{MAT_BAR},{_f(val('PBAR', pid, 'A', a))},"
                     f"{_f(val('PBAR', pid, 'I1', i1))},{_f(val('PBAR', pid, 'I2', i2))},"
                     f"{_f(val('PBAR', pid, 'J', j))},2.0")
    for pid, t in PSHELL_T.items():
        lines.append(f"PSHELL,{pid},{MAT_SKIN},{_f(val('PSHELL', pid, 'T', t))},{MAT_SKIN},,"
                     f"{MAT_SKIN}")
    lines.append(f"PELAS,41,{_f(val('PELAS', 41, 'K', PYLON_K))}")
    groups = {"fuselage": [], "spar": [], "skin": [], "tail": [], "engine": []}
    gid = [0]
    eid = [10000]   # automatic element ids above the CELAS2 (8xx) and CONM2 (9xx) ids

    def grid(x, y, z, group):
        gid[0] += 1
        lines.append(f"GRID,{gid[0]},,{_f(x)},{_f(y)},{_f(z)}")
        groups[group].append(gid[0])
        return gid[0]

    def bar(a, b, pid, v=(0.0, 0.0, 1.0)):
        eid[0] += 1
        lines.append(f"CBAR,{eid[0]},{pid},{a},{b},{v[0]},{v[1]},{v[2]}")

    fus = [grid(x, 0.0, 0.0, "fuselage") for x in np.linspace(0.0, 12.0, n_fus + 1)]
    for a, b in zip(fus[:-1], fus[1:]):
        bar(a, b, 1)
    root = fus[int(round(n_fus * 5.0 / 12.0))]
    x_root, chord, span = 5.0, 1.6, 8.0
    spar_grids = []
    for side, (p_in, p_out, p_skin) in ((1.0, (12, 14, 22)), (-1.0, (11, 13, 21))):
        prev = root
        prev_row = None
        for s, y in enumerate(np.linspace(0.5, span, n_span)):
            xs = x_root + 0.3 * y / span          # slight sweep
            row = [grid(xs + (c / n_chord - 0.5) * chord * (1 - 0.4 * y / span), side * y, 0.0,
                        "spar" if c == n_chord // 2 else "skin") for c in range(n_chord + 1)]
            spar = row[n_chord // 2]
            spar_grids.append(spar)
            bar(prev, spar, p_in if y <= span / 2 else p_out)
            if prev_row is not None:
                for c in range(n_chord):
                    eid[0] += 1
                    quad = (prev_row[c], prev_row[c + 1], row[c + 1], row[c])
                    if side < 0:
                        quad = quad[::-1]
                    lines.append(f"CQUAD4,{eid[0]},{p_skin},{quad[0]},{quad[1]},{quad[2]},{quad[3]}")
            else:
                for c in (0, n_chord):
                    bar(row[c], spar, 1)      # stiff root rib
            prev, prev_row = spar, row
            if s == n_span // 3:
                eng = grid(xs, side * y, 0.0, "engine")   # coincident: springs stay rigid-body free
                for c in (1, 2, 3):   # pylon: CELAS1 on PELAS 41 (translations), CELAS2 rotations
                    eid[0] += 1
                    lines.append(f"CELAS1,{eid[0]},41,{spar},{c},{eng},{c}")
                for c in (4, 5, 6):
                    k_rot = val("CELAS2", 800 + 3 * int(side > 0) + c, "K", PYLON_K_ROT)
                    lines.append(f"CELAS2,{800 + 3 * int(side > 0) + c},{_f(k_rot)},{spar},{c},{eng},{c}")
                lines.append(f"CONM2,{900 + int(side > 0)},{eng},,{_f(val('CONM2', 900 + int(side > 0), 'M', ENGINE_MASS))},"
                             f"-0.8,0.,-0.5,\n,{_f(2.0)},,{_f(4.0)},,,{_f(4.0)}")
    tail = fus[-1]
    for side in (1.0, -1.0):
        prev = tail
        for y in (1.0, 2.0, 3.0):
            g = grid(12.0, side * y, 0.3, "tail")
            bar(prev, g, 31)
            prev = g
    prev = tail
    for z in (0.8, 1.6, 2.4):
        g = grid(12.0, 0.0, z, "tail")
        bar(prev, g, 32, v=(1.0, 0.0, 0.0))
        prev = g
    lines.append(f"CONM2,910,{fus[2]},,{_f(val('CONM2', 910, 'M', 120.0))}")
    lines.append(f"CONM2,911,{fus[7]},,{_f(80.0)}")
    if fuel > 0:
        for k, g in enumerate(spar_grids):
            lines.append(f"CONM2,{950 + k},{g},,{_f(fuel / len(spar_grids))}")
    lines.append("ENDDATA")
    path.write_text("\n".join(lines) + "\n")
    return {"path": path, "grids": {k: np.array(v) for k, v in groups.items()}, "n_grids": gid[0]}


def _spread(items):
    """Items reordered so that every prefix is spread over the list (van der Corput order)."""
    n = len(items)
    if n == 0:
        return []
    key = []
    for i in range(n):
        x, f, k = 0.0, 0.5, i + 1
        while k:
            x += f * (k & 1)
            k >>= 1
            f /= 2
        key.append(x)
    return [items[i] for i in np.argsort(key, kind="stable")]


def sensor_dofs(groups, n: int = 120):
    """(grid, component) of ``n`` measured DOFs, taken in turn from the sensor families (z of the
    wing skin and spar, x/y/z of the fuselage, y/z of the tail, x/y/z of the engines, y and x of
    the spar, y of the skin), each family in an order that spreads its sensors along it."""
    wing = np.concatenate([groups["skin"], groups["spar"]])
    families = [[(g, 3) for g in wing],
                [(g, c) for g in groups["fuselage"] for c in (1, 2, 3)],
                [(g, c) for g in groups["tail"] for c in (2, 3)],
                [(g, c) for g in groups["engine"] for c in (1, 2, 3)],
                [(g, 2) for g in groups["spar"]], [(g, 1) for g in groups["spar"]],
                [(g, 2) for g in groups["skin"]]]
    queues = [_spread(f) for f in families]
    picks = []
    while len(picks) < n and any(queues):
        for q in queues:
            if q and len(picks) < n:
                picks.append(q.pop(0))
    if len(picks) < n:
        raise ValueError(f"the model has only {len(picks)} sensor DOFs; {n} were asked for")
    order = np.lexsort((np.array([p[1] for p in picks]), np.array([p[0] for p in picks])))
    return np.array([picks[i][0] for i in order]), np.array([picks[i][1] for i in order])


def write_cantilever_deck(path, *, ratio: float = 1.0, coupling: float = 0.42, n_elem: int = 10):
    """Clamped CBAR beam (root grid SPC 123456) with first two bending frequencies f2 / f1 = ratio
    (I2 = ratio^2 I1), a tip CONM2 (eid 99) with inertia, a PBUSH-free design: PBAR 1, MAT1 1."""
    i1 = 1e-6
    lines = ["SOL 103", "CEND", "SPC = 1", "BEGIN BULK", "PARAM,COUPMASS,1",
             f"MAT1,1,{_f(70e9)},{_f(27e9)},,2700.",
             f"PBAR,1,1,{_f(2e-3)},{_f(i1)},{_f(i1 * ratio ** 2)},{_f(2e-6)},1.0"]
    for k in range(n_elem + 1):
        lines.append(f"GRID,{k + 1},,{_f(0.3 * k)},0.,0.")
    for k in range(n_elem):
        lines.append(f"CBAR,{k + 1},1,{k + 1},{k + 2},0.,0.,1.")
    # tip CONM2 with offset and product of inertia I32: couples the two bending planes
    lines.append(f"CONM2,99,{n_elem + 1},,{_f(5.0)},0.,0.03,0.02,\n,{_f(0.2)},,{_f(2.0)},,{_f(coupling)},{_f(2.0)}")
    lines.append("SPC1,1,123456,1")
    lines.append("ENDDATA")
    path.write_text("\n".join(lines) + "\n")
    return path


def synthetic_gvt(truth_modes, groups, test_modes, *, rng=None, f_noise=0.0, s_noise=0.0,
                  n_dofs: int = 120, source: str = "synthetic"):
    """A 'measured' GVT Dataset from a truth modes Dataset at the sensor DOFs of
    :func:`sensor_dofs`, with the correlation issue's noise model: frequencies times
    (1 + f_noise N(0,1)), shapes plus s_noise * rms(shape) * N(0,1) per DOF."""
    from structures.gvt import make_gvt_dataset
    grid, comp = sensor_dofs(groups, n_dofs)
    key = truth_modes["grid"].values * 10 + truth_modes["component"].values
    index = np.array([np.flatnonzero(key == g * 10 + c)[0] for g, c in zip(grid, comp)])
    sub = truth_modes.sel(mode=list(test_modes)).isel(dof=index)
    freq, shape = sub["frequency"].values.copy(), sub["shape"].values.copy()
    if rng is not None:
        freq = freq * (1 + f_noise * rng.standard_normal(freq.size))
        rms = np.sqrt(np.mean(shape ** 2, axis=1, keepdims=True))
        shape = shape + s_noise * rms * rng.standard_normal(shape.shape)
    return make_gvt_dataset(freq, shape, grid, comp, mode=list(test_modes), source=source)
