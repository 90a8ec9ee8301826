"""The shipped BAH example deck for tests: its path and an edited copy with its INCLUDE files."""
from __future__ import annotations

import shutil
from pathlib import Path

DECK = Path(__file__).resolve().parents[2] / "data" / "bah_wing" / "bah_plane.bdf"
BAH_FILES = ("bah_plane.bdf", "structure_bah.inc", "aero_bah.inc", "interface_bah.inc")


def deck_copy(folder: Path, edit) -> Path:
    """The BAH deck with its INCLUDE files in ``folder``, the main file edited by ``edit``."""
    for name in BAH_FILES:
        shutil.copy(DECK.parent / name, folder / name)
    path = folder / "bah_plane.bdf"
    path.write_text(edit(path.read_text()))
    return path
