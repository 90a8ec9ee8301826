"""Write the practitioner-style built-up wing deck of issue 10 (deterministic; run to regenerate).

    python tests/data/practitioner_wing/make_deck.py

A 5 m cantilever wing box (two spars, eleven ribs, depth tapering 0.14 -> 0.08 m) with every trait
of the deck reported in the issue, which MSC Nastran solves and our old global AUTOSPC threshold
rejected as a mechanism:

* a very thin film skin (PSHELL T = 1.-5 m, a soft MAT1) over aluminium spar and rib webs of
  CQUAD4, the outboard bay of CTRIA3;
* spar caps of CBEAM with tapered PBEAMs written small-field with large-field ``*`` continuations;
  the aluminium MAT1* is large-field; reals without the E (``4.3444-5``);
* reference-axis grids: an RBE3 (REFC 123456) at every rib carrying a CONM2, the root clamped
  through an RBE2 from the root reference grid;
* ``AUTOSPC = YES`` in the case control, PARAM AUTOSPC / LMODES / GRDPNT / NEWSEQ, EIGRL, an
  SPCADD of two SPC1 sets, and an INCLUDE chain wing.bdf -> wing_geometry.inc -> wing_props.inc.

``mystran=True`` writes the same model as one file MYSTRAN 18 reads (no INCLUDE; small-field PBAR
with the mean of each tapered PBEAM's end values, which is how our reader idealises a tapered
PBEAM; CBAR instead of CBEAM, whose torsional inertia our lumped mass omits anyway; no
case-control AUTOSPC), for the cross-check in tests/structures/test_singularity.py.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[2]))

from structures.bulk_text import card  # noqa: E402  (the repository root is put on the path above)

SPAN, N_BAY, N_CHORD = 5.0, 20, 4          # 0.25 m bays, ribs every second station
X_FRONT, BOX_WIDTH = 0.30, 0.40
DEPTH_ROOT, DEPTH_TIP = 0.14, 0.08
CAP_AREA = (2.0e-3, 6.0e-4)                # root, tip
REF_MASS = 3.0                             # CONM2 on each rib's reference-axis grid [kg]


def nastran_real(value: float) -> str:
    """A real in Nastran's short exponent form without the E (4.3444-5), at most 8 characters."""
    mantissa, exponent = f"{value:.4e}".split("e")
    mantissa = mantissa.rstrip("0")
    text = f"{mantissa}{int(exponent):+d}"
    return text if len(text) <= 8 else f"{value:.2e}".replace("e", "")


def _large_field(v) -> str:
    if v is None:
        return " " * 16
    if isinstance(v, (int, np.integer)):
        return f"{int(v):<16d}"
    if isinstance(v, str):
        return f"{v:<16s}"
    return f"{float(v):<16.8E}"


def large_continuations(*values) -> list[str]:
    """Large-field continuation lines (``*`` in column 1, 4 fields of 16 characters each)."""
    vals = list(values)
    return [("*       " + "".join(_large_field(v) for v in vals[k:k + 4])).rstrip()
            for k in range(0, len(vals), 4)]


def large(name: str, *values) -> str:
    """A large-field card: 4 fields of 16 characters per line, ``*`` continuations."""
    head = f"{name + '*':<8s}" + "".join(_large_field(v) for v in values[:4])
    return "\n".join([head.rstrip(), *large_continuations(*values[4:])])


def stations():
    y = np.linspace(0.0, SPAN, N_BAY + 1)
    depth = DEPTH_ROOT + (DEPTH_TIP - DEPTH_ROOT) * y / SPAN
    return y, depth


def grid_id(surface: str, j: int, i: int) -> int:
    """Grid ids: top 1000+, bottom 2000+, mid-height (spar / rib webs) 3000+, reference axis 9000+."""
    return {"top": 1000, "bottom": 2000, "mid": 3000}[surface] + 10 * j + i


def geometry(mystran: bool) -> list[str]:
    y, depth = stations()
    lines = ["$ grids: skin / cap (top, bottom), web mid-height, reference axis"]
    for j in range(N_BAY + 1):
        rib = j % 2 == 0
        for i in range(N_CHORD + 1):
            x = X_FRONT + BOX_WIDTH * i / N_CHORD
            lines.append(card("GRID", grid_id("top", j, i), None, x, y[j], 0.5 * depth[j]))
            lines.append(card("GRID", grid_id("bottom", j, i), None, x, y[j], -0.5 * depth[j]))
            if i in (0, N_CHORD) or rib:
                lines.append(card("GRID", grid_id("mid", j, i), None, x, y[j], 0.0))
        if rib:
            lines.append(card("GRID", 9000 + j, None, X_FRONT + 0.5 * BOX_WIDTH, y[j], 0.0))
    eid = 1
    lines.append("$ film skin: CQUAD4, CTRIA3 in the outboard bay")
    for j in range(N_BAY):
        for surface in ("top", "bottom"):
            for i in range(N_CHORD):
                g = [grid_id(surface, j, i), grid_id(surface, j, i + 1),
                     grid_id(surface, j + 1, i + 1), grid_id(surface, j + 1, i)]
                if j == N_BAY - 1:
                    lines.append(card("CTRIA3", eid, 1, g[0], g[1], g[2]))
                    lines.append(card("CTRIA3", eid + 1, 1, g[0], g[2], g[3]))
                    eid += 2
                else:
                    lines.append(card("CQUAD4", eid, 1, *g))
                    eid += 1
    lines.append("$ spar webs")
    eid = 1001
    for j in range(N_BAY):
        for i in (0, N_CHORD):
            for upper, lower in (("top", "mid"), ("mid", "bottom")):
                lines.append(card("CQUAD4", eid, 2, grid_id(upper, j, i), grid_id(upper, j + 1, i),
                                  grid_id(lower, j + 1, i), grid_id(lower, j, i)))
                eid += 1
    lines.append("$ rib webs")
    eid = 2001
    for j in range(0, N_BAY + 1, 2):
        for i in range(N_CHORD):
            for upper, lower in (("top", "mid"), ("mid", "bottom")):
                lines.append(card("CQUAD4", eid, 3, grid_id(upper, j, i), grid_id(upper, j, i + 1),
                                  grid_id(lower, j, i + 1), grid_id(lower, j, i)))
                eid += 1
    lines.append("$ spar caps: " + ("CBAR" if mystran else "CBEAM") + ", one tapered section per bay")
    eid = 3001
    for j in range(N_BAY):
        for i in (0, N_CHORD):
            for surface in ("top", "bottom"):
                lines.append(card("CBAR" if mystran else "CBEAM", eid, 101 + j,
                                  grid_id(surface, j, i), grid_id(surface, j + 1, i), 0.0, 0.0, 1.0))
                eid += 1
    lines.append("$ reference axis: RBE3 (REFC 123456) at the ribs, RBE2 clamp at the root")
    for j in range(2, N_BAY + 1, 2):
        corners = [grid_id(s, j, i) for s in ("top", "bottom") for i in (0, N_CHORD)]
        lines.append(card("RBE3", 5000 + j, None, 9000 + j, 123456, 1.0, 123, *corners))
        lines.append(card("CONM2", 6000 + j, 9000 + j, 0, REF_MASS, 0.02, 0.0, 0.0, None,
                          0.05, 0.0, 0.3, 0.0, 0.0, 0.3))
    root = [grid_id(s, 0, i) for s in ("top", "bottom") for i in range(N_CHORD + 1)]
    root += [grid_id("mid", 0, i) for i in range(N_CHORD + 1)]
    lines.append(card("RBE2", 5000, 9000, 123456, *root))
    if not mystran:
        lines.append("INCLUDE 'wing_props.inc'")
    return lines


def cap_section(y: float):
    """Flat spar-cap flange at span y: width b = sqrt(20 A), thickness t = A / b.

    Returns (A, I1, I2, J, b, t) with I1 = b t^3/12 (vertical bending, plane 1 holds the
    orientation vector +z), I2 = t b^3/12 and the thin-strip torsion constant J = b t^3/3.
    """
    a = CAP_AREA[0] + (CAP_AREA[1] - CAP_AREA[0]) * y / SPAN
    b = np.sqrt(20.0 * a)
    t = a / b
    return a, b * t ** 3 / 12.0, t * b ** 3 / 12.0, b * t ** 3 / 3.0, b, t


def properties(mystran: bool) -> list[str]:
    y, depth = stations()
    lines = ["$ aluminium (large field) and a soft film"]
    lines.append(large("MAT1", 1, 7.1e10, None, 0.33, 2810.0))
    lines.append(card("MAT1", 2, "2.5+9", None, 0.34, "1420."))
    lines.append(card("PSHELL", 1, 2, nastran_real(1.0e-5)))       # membrane-only film
    lines.append(card("PSHELL", 2, 1, nastran_real(2.0e-3), 1, None, None))
    lines.append(card("PSHELL", 3, 1, nastran_real(1.2e-3), 1, None, None))
    lines.append("$ spar caps: flat flanges (width 20 x thickness), tapered along each bay")
    for j in range(N_BAY):
        (a1, i1a, i2a, ja, b1, t1), (a2, i1b, i2b, jb, _, _) = cap_section(y[j]), cap_section(y[j + 1])
        if mystran:
            mean = [0.5 * (u + v) for u, v in zip((a1, i1a, i2a, ja), (a2, i1b, i2b, jb))]
            lines.append(card("PBAR", 101 + j, 1, *(nastran_real(v) for v in mean)))
            continue
        head = card("PBEAM", 101 + j, 1, *(nastran_real(v) for v in (a1, i1a, i2a)), 0.0,
                    nastran_real(ja), 0.0)
        corners = (t1 / 2, b1 / 2, t1 / 2, -b1 / 2, -t1 / 2, b1 / 2, -t1 / 2, -b1 / 2)  # C, D, E, F
        lines += [head, *large_continuations(*corners, "NO", 1.0, a2, i1b, i2b, 0.0, jb, 0.0)]
    return lines


def case_control(mystran: bool) -> list[str]:
    lines = ["SOL 103", "CEND", "TITLE = PRACTITIONER WING: FILM SKIN OVER SPARS AND RIBS",
             "ECHO = NONE", "SPC = 100", "METHOD = 1", "DISP(PLOT) = ALL"]
    if not mystran:
        lines.insert(4, "AUTOSPC = YES")
    return lines + ["BEGIN BULK"]


def bulk_head(mystran: bool) -> list[str]:
    lines = [card("EIGRL", 1, None, None, 10)]
    if not mystran:
        lines += ["PARAM,AUTOSPC,YES", "PARAM,LMODES,10", "PARAM,GRDPNT,0", "PARAM,NEWSEQ,-1"]
    lines += [card("SPCADD", 100, 11, 12), card("SPC1", 11, 123, 9000), card("SPC1", 12, 456, 9000)]
    return lines


def write_deck(folder: Path, *, mystran: bool = False) -> Path:
    """Write the deck into ``folder``; return the path of the main file.

    Parameters
    ----------
    folder : Path
    mystran : bool, write the single-file MYSTRAN variant ``wing_mystran.bdf`` instead.
    """
    folder.mkdir(parents=True, exist_ok=True)
    if mystran:
        path = folder / "wing_mystran.bdf"
        text = case_control(True) + bulk_head(True) + geometry(True) + properties(True)
        path.write_text("\n".join(text + ["ENDDATA"]) + "\n")
        return path
    (folder / "wing_props.inc").write_text("\n".join(properties(False)) + "\n")
    (folder / "wing_geometry.inc").write_text("\n".join(geometry(False)) + "\n")
    path = folder / "wing.bdf"
    text = case_control(False) + bulk_head(False) + ["INCLUDE 'wing_geometry.inc'", "ENDDATA"]
    path.write_text("\n".join(text) + "\n")
    return path


if __name__ == "__main__":
    print(write_deck(HERE))
