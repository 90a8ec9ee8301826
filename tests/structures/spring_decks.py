"""A three-grid spring chain with one mass: the smallest model with fewer degrees of freedom
carrying mass than degrees of freedom (tests of how many modes a model has)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

#: Its one mode [Hz], condensed by hand: grid 2 (mass 2) on 100 to grid 1, itself on 50 to
#: ground, and on 20 to grid 3, itself on 30 to ground: k = 100*50/150 + 20*30/50.
CHAIN_FREQUENCY = float(np.sqrt((100.0 * 50.0 / 150.0 + 20.0 * 30.0 / 50.0) / 2.0) / (2 * np.pi))


def spring_chain(path: Path, nd: int | None = None, *, mass: bool = True) -> Path:
    """Write the chain (x motion only, CELAS2 springs, one CONM2 at grid 2, left out when not
    ``mass``) to ``path``, with an EIGRL asking ``nd`` modes when given; returns ``path``."""
    lines = ["SOL 103", "CEND"] + (["METHOD = 1"] if nd else []) + ["BEGIN BULK"]
    lines += [f"EIGRL,1,,,{nd}"] if nd else []
    lines += ["GRID,1,,0.,0.,0.,,23456", "GRID,2,,1.,0.,0.,,23456", "GRID,3,,2.,0.,0.,,23456",
              "CELAS2,1,50.,1,1", "CELAS2,2,100.,1,1,2,1", "CELAS2,3,20.,2,1,3,1",
              "CELAS2,4,30.,3,1"] + (["CONM2,9,2,,2."] if mass else []) + ["ENDDATA"]
    path.write_text("\n".join(lines) + "\n")
    return path
