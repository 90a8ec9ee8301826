"""A six-mass spring chain deck for the diagnose command and case-table tests."""
from __future__ import annotations

from pathlib import Path

#: CONM2 masses of the chain's six grids (100, 200, ..., 600).
MASSES = (1.0, 1.2, 1.4, 1.0, 1.2, 1.4)


def chain_deck(path: Path, extra=()) -> None:
    """Six grids along x tied by CELAS2 springs in x, y, z, CONM2 masses, rotations fixed;
    ``extra`` cards are added before ENDDATA."""
    cards = ["CEND", "BEGIN BULK"]
    for i, m in enumerate(MASSES):
        cards += [f"GRID,{100 * (i + 1)},,{float(i)},0.,0.", f"CONM2,{900 + i},{100 * (i + 1)},,{m}"]
    for i in range(len(MASSES) - 1):
        for c, k in ((1, 4.0e4), (2, 1.0e4), (3, 2.5e4)):
            cards.append(f"CELAS2,{10 * i + c},{k * (1.0 + 0.1 * i)},{100 * (i + 1)},{c},"
                         f"{100 * (i + 2)},{c}")
    cards += ["SPC1,1,456," + ",".join(str(100 * (i + 1)) for i in range(len(MASSES))),
              *extra, "ENDDATA"]
    Path(path).write_text("\n".join(cards) + "\n")
