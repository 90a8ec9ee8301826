"""Small bulk-data decks written on the fly for the aero tests."""
from __future__ import annotations

from pathlib import Path

DATA = Path(__file__).resolve().parents[1] / "data"
BAH = DATA / "bah_plane" / "bah_plane.bdf"


def write_deck(path: Path, bulk: str, aero: str = "AERO,0,1.,2.,1.225,0,0") -> Path:
    """Write a SOL 145 deck with the given bulk lines (one card per line, free field)."""
    text = "SOL 145\nCEND\nBEGIN BULK\n" + aero + "\n" + bulk.strip() + "\nENDDATA\n"
    path.write_text(text)
    return path


def wing_grids(nx: int = 3, ny: int = 4, chord: float = 2.0, span: float = 6.0,
               first: int = 1) -> str:
    """GRID cards on a regular nx x ny net over a rectangular planform (basic frame)."""
    lines = []
    gid = first
    for j in range(ny):
        for i in range(nx):
            x = -0.2 + (chord + 0.4) * i / (nx - 1)
            y = span * j / (ny - 1)
            lines.append(f"GRID,{gid},,{x:.6f},{y:.6f},0.")
            gid += 1
    return "\n".join(lines)
