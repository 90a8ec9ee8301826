"""The second structure of the blind study: a free-free glider-like beam frame (SI: m, kg, N, s).

Different from the X-56A-class flying wing in layout, units and joints:

* fuselage: eight CBARs along x (grids 1001-1009, x = 0 .. 8 m, one PBAR 11: a member of eight
  elements), the pilot (80 kg) at 1002;
* wings: elastic axis at x = 3 m from the fuselage grid 1004 out to y = +-7.5 m, ten stations per
  side (right EA 2001-2010, leading edge 2101-2110, trailing edge 2201-2210; left +1000), one
  PBAR per segment (right 21-30, left 31-40), sections geometric root to tip; every station's
  leading- and trailing-edge grids tied to its EA grid by an RBE2 (right 7001-7010, left
  7101-7110) and carrying mass (leading-edge structure, ailerons and flaps), so the chord joints
  carry inertia;
* horizontal tail (4001-4004 right, 4101-4104 left, PBAR 51 / 52) and fin (4201-4203, PBAR 53)
  at the fuselage grid 1008;
* a store under each wing at station 4: a pylon CBAR (PBAR 61 / 62) from the EA grid down to
  5001 (left 5101) and the 40 kg store at 5002 (5102) on an RBE2 (7201, 7202);
* two main-gear struts from the fuselage grid 1004 (grids 6001-6002 right, 6101-6102 left, two
  CBARs each, PBAR 71 / 72) with 15 kg wheels;
* all mass is CONM2 (MAT1 RHO = 0); no SPC (free-free); E = 70 GPa, nu = 0.33.

88 grids, 583 kg; the ``N_TEST`` = 20 measured elastic modes span 2.8-25 Hz (our solver).
"""
from __future__ import annotations

from pathlib import Path

from structures.bulk_text import card

UNITS = "si"
#: Elastic modes "measured" by the GVT.
N_TEST = 20
E, NU = 7.0e10, 0.33
FUSELAGE_X = tuple(float(x) for x in range(9))
WING_X, WING_Y = 3.0, tuple(0.75 * (i + 1) for i in range(10))
CHORD_ROOT, CHORD_TIP = 1.2, 0.6
TAIL_Y, FIN_Z = (0.5, 1.0, 1.5, 2.0), (0.5, 1.0, 1.5)
STORE_STATION = 4
#: (A, I1 vertical bending, I2 in-plane bending, J) in m^2, m^4
FUSELAGE = (5.0e-3, 6.0e-5, 6.0e-5, 8.0e-5)
WING_ROOT = (2.5e-3, 2.0e-5, 2.0e-4, 1.2e-5)
WING_TIP = (8.0e-4, 1.5e-6, 1.5e-5, 1.0e-6)
TAIL = (8.0e-4, 1.5e-6, 1.0e-5, 1.5e-6)
FIN = (8.0e-4, 3.0e-6, 1.0e-5, 2.0e-6)
PYLON = (1.0e-3, 3.0e-7, 3.0e-7, 4.0e-7)
GEAR = (8.0e-4, 2.0e-7, 4.0e-7, 3.0e-7)


def _sides():
    """(grid offset, pid offset, y sign) of the right and left side."""
    return ((0, 0, 1.0), (1000, 10, -1.0))


def _chord(y: float) -> float:
    return CHORD_ROOT + (CHORD_TIP - CHORD_ROOT) * abs(y) / WING_Y[-1]


def grids() -> dict[int, tuple[float, float, float]]:
    """Every grid id -> (x, y, z) in m."""
    g = {1001 + i: (x, 0.0, 0.0) for i, x in enumerate(FUSELAGE_X)}
    for side, _, s in _sides():
        for i, y in enumerate(WING_Y):
            c = _chord(y)
            g[2001 + side + i] = (WING_X, s * y, 0.0)
            g[2101 + side + i] = (WING_X - 0.35 * c, s * y, 0.0)
            g[2201 + side + i] = (WING_X + 0.65 * c, s * y, 0.0)
    for k, s in ((0, 1.0), (100, -1.0)):
        g.update({4001 + k + i: (7.0, s * y, 0.0) for i, y in enumerate(TAIL_Y)})
        y = s * WING_Y[STORE_STATION - 1]
        g[5001 + k] = (WING_X, y, -0.3)
        g[5002 + k] = (WING_X + 0.2, y, -0.45)
        g[6001 + k] = (WING_X + 0.05, s * 0.3, -0.5)
        g[6002 + k] = (WING_X + 0.1, s * 0.6, -1.0)
    g.update({4201 + i: (7.0, 0.0, z) for i, z in enumerate(FIN_Z)})
    return g


def _geometric(a, b, t: float) -> tuple:
    return tuple(x * (y / x) ** t for x, y in zip(a, b))


def bulk() -> list[str]:
    """The analysis deck's bulk data (GRID, MAT1, PBAR, CBAR, RBE2, CONM2)."""
    xyz = grids()
    up, fore = (0.0, 0.0, 1.0), (1.0, 0.0, 0.0)
    props = {11: FUSELAGE, 51: TAIL, 52: TAIL, 53: FIN, 61: PYLON, 62: PYLON, 71: GEAR, 72: GEAR}
    for _, p, _ in _sides():
        props.update({21 + p + i: _geometric(WING_ROOT, WING_TIP, (i + 0.5) / len(WING_Y))
                      for i in range(len(WING_Y))})
    bars = [(1001 + i, 11, 1001 + i, 1002 + i, up) for i in range(len(FUSELAGE_X) - 1)]
    rigid, masses = [], []
    for side, p, _ in _sides():
        line = [1004] + [2001 + side + i for i in range(len(WING_Y))]
        bars += [(2001 + side + i, 21 + p + i, a, b, up)
                 for i, (a, b) in enumerate(zip(line[:-1], line[1:]))]
        rigid += [(7001 + side // 10 + i, 2001 + side + i, (2101 + side + i, 2201 + side + i))
                  for i in range(len(WING_Y))]
        for i, y in enumerate(WING_Y):
            c = _chord(y)
            masses += [(8001 + side + i, 2001 + side + i, 7.0 * c, (0.0, 0.0, 0.0),
                        (0.5 * c, 0.05, 0.5 * c)),
                       (8101 + side + i, 2101 + side + i, 1.5 * c, (0.0, 0.0, 0.0), None),
                       (8201 + side + i, 2201 + side + i, 2.0 * c, (0.0, 0.0, 0.0), None)]
    for k, (side, _, s) in enumerate(_sides()):
        g = 100 * k
        tail = [1008] + [4001 + g + i for i in range(len(TAIL_Y))]
        bars += [(4001 + g + i, 51 + k, a, b, up) for i, (a, b) in enumerate(zip(tail[:-1], tail[1:]))]
        masses += [(8401 + 10 * k + i, 4001 + g + i, 2.0, (0.0, 0.0, 0.0), None)
                   for i in range(len(TAIL_Y))]
        bars.append((5001 + g, 61 + k, 2001 + side + STORE_STATION - 1, 5001 + g, fore))
        rigid.append((7201 + k, 5001 + g, (5002 + g,)))
        masses += [(8501 + 10 * k, 5001 + g, 2.0, (0.0, 0.0, 0.0), None),
                   (8502 + 10 * k, 5002 + g, 40.0, (0.0, 0.0, 0.0), (0.4, 4.0, 4.0))]
        bars += [(6001 + g, 71 + k, 1004, 6001 + g, fore), (6002 + g, 71 + k, 6001 + g, 6002 + g, fore)]
        masses += [(8601 + 10 * k, 6001 + g, 3.0, (0.0, 0.0, 0.0), None),
                   (8602 + 10 * k, 6002 + g, 15.0, (0.0, 0.0, 0.0), (0.3, 0.5, 0.3))]
    fin = [1008] + [4201 + i for i in range(len(FIN_Z))]
    bars += [(4201 + i, 53, a, b, fore) for i, (a, b) in enumerate(zip(fin[:-1], fin[1:]))]
    masses += [(8701 + i, 4201 + i, 1.5, (0.0, 0.0, 0.0), None) for i in range(len(FIN_Z))]
    masses += [(8801 + i, 1001 + i, 20.0, (0.0, 0.0, 0.0), (2.0, 2.0, 2.0))
               for i in range(len(FUSELAGE_X))]
    masses.append((8901, 1002, 80.0, (0.0, 0.0, 0.3), (8.0, 8.0, 4.0)))
    out = ["$ glider-like frame (tests/pipeline/diagnose/truth/frame.py): m, kg, N, s",
           card("MAT1", 1, E, None, NU, 0.0)]
    out += [card("GRID", gid, None, *p) for gid, p in sorted(xyz.items())]
    out += [card("PBAR", pid, 1, *sec) for pid, sec in sorted(props.items())]
    out += [card("CBAR", eid, pid, a, b, *v) for eid, pid, a, b, v in sorted(bars)]
    out += [card("RBE2", eid, gn, 123456, *dep) for eid, gn, dep in sorted(rigid)]
    for eid, gid, m, off, inertia in sorted(masses):
        i11, i22, i33 = inertia or (0.0, 0.0, 0.0)
        out.append(card("CONM2", eid, gid, 0, m, *off, None, i11, 0.0, i22, 0.0, 0.0, i33))
    return out


def sensors() -> list[tuple[int, int]]:
    """The 120 measured translations (grid, component 1..3), sorted."""
    out = []
    for side, _, _ in _sides():
        out += [(g + side + i, 3) for g in (2101, 2201) for i in range(len(WING_Y))]
        out += [(2001 + side + i, 3) for i in (1, 3, 5, 7, 9)]
        out += [(2001 + side + i, 1) for i in (2, 5, 9)] + [(2001 + side + i, 2) for i in (4, 9)]
    out += [(1001 + i, c) for i in range(len(FUSELAGE_X)) for c in (2, 3)]
    out += [(1001, 1), (1005, 1), (1009, 1)]
    for g in (0, 100):
        out += [(4001 + g + i, 3) for i in range(len(TAIL_Y))] + [(4004 + g, 1), (4004 + g, 2)]
        out += [(5002 + g, c) for c in (1, 2, 3)] + [(5001 + g, 2), (5001 + g, 3)]
        out += [(6001 + g, c) for c in (1, 2, 3)] + [(6002 + g, c) for c in (1, 2, 3)]
    out += [(4201 + i, 2) for i in range(len(FIN_Z))] + [(4203, 1), (4203, 3)]
    return sorted(out)


def write_frame(folder: Path) -> Path:
    """Write the analysis deck ``frame.bdf`` (SOL 103, EIGRL) into ``folder``; returns its path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    lines = ["SOL 103", "CEND", "TITLE = GLIDER-LIKE FRAME", "METHOD = 1", "BEGIN BULK",
             *bulk(), card("EIGRL", 1, None, None, 6 + 2 * N_TEST), "ENDDATA"]
    path = folder / "frame.bdf"
    path.write_bytes(("\n".join(lines) + "\n").encode("ascii"))
    return path

