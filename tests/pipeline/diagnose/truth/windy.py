"""The fourth structure of the blind study: a wind-tunnel wing from elsewhere, a stick model.

The University of Bristol WINDY wing with its folding wingtip locked (``tests/data/windy_fwt``,
SOURCES there): a spar of 104 CBEAMs on three PBEAML BAR sections, 23 CONM2 with offsets in
rotated frames, rib points hung on the spar by eleven RBE2s, the tip masses carried by three
RBE3s, the hinge an RBE2 (300) between two coincident grids, clamped at grid 1, SI units.
Neither this project's generators nor its author made it.

The analysis deck is the public deck written back in one file (``write_windy``): the workflow
sees its PBEAML and CBEAM cards. The truth starts from the same deck with each PBEAML written as
the PBAR of its section and each CBEAM as a CBAR (``truth_start``: exact for these prismatic,
unwarped, offset-free beams; tests/structures/test_public_decks.py matches the same rewrite
with MYSTRAN to 7.2e-5), so the generator's PBAR scatter, tapers and bows act on it; it is
solved by our solver.

Kinds: ``KINDS`` here. The rib RBE2s hang massless grids (a flexible joint there moves no mass
and changes no mode) and the hinge is the slow hinge test's (tests/pipeline/diagnose/
test_hinge_fwt.py), so no joint. The spar's grids lie on one line, where a brace (the
``outside`` kind, massless) would change no bending or torsion mode: braces join the rib points
(``brace_grids``: the rib RBE2s' dependent grids, fore and aft of the spar), as a fairing or a
skin panel carrying load between two ribs would. The GVT: ``N_TEST`` modes at all three
translations of 40 of the free grids (120 DOFs, evenly over the ids; the clamped grid and the
RBE3 mass points left out).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from structures.common.nastran import read_pynastran
from structures.sections import section_fields

UNITS = "si"
N_TEST = 10
#: Clamped: no rigid-body mode.
N_RIGID = 0
KINDS = ("lumped_mass", "member_taper", "member_curvature", "boundary_stiffness", "none",
         "outside")
DECK = Path(__file__).resolve().parents[3] / "data" / "windy_fwt" / "sol103.bdf"
#: The clamped grid (SPC 2) and the RBE3 reference grids that carry the tip masses.
ROOT, MASS_POINTS = (1,), (400, 401, 402)
#: The RBE2 that locks the hinge (its dependent grid is no rib point).
HINGE = 300
N_GRIDS = 40


def write_windy(folder: Path) -> Path:
    """Write the analysis deck ``windy.bdf`` (the public deck, includes resolved, EIGRL for the
    test modes and 8 more) into ``folder``; returns its path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    bdf = read_pynastran(DECK)
    bdf.methods[next(iter(bdf.methods))].nd = N_TEST + 8
    path = folder / "windy.bdf"
    bdf.write_bdf(str(path), enddata=True, size=16)
    return path


def as_bars(bdf) -> None:
    """In place: each PBEAML of a parsed deck as the PBAR of its section
    (:func:`structures.sections.section_fields`) and each CBEAM as a CBAR (same ids, ends and
    orientation vector x; no warping, taper or offsets on this deck)."""
    for pid, prop in list(bdf.properties.items()):
        if prop.type == "PBEAML":
            f = section_fields("PBEAML", pid, prop.mid, prop.beam_type, prop.dim, prop.xxb,
                               prop.nsm)
            del bdf.properties[pid]
            bdf.add_pbar(pid, f["MID"], A=f["A"], i1=f["I1"], i2=f["I2"], i12=f["I12"], j=f["J"],
                         nsm=f["NSM"] or 0.0)
    for eid, elem in list(bdf.elements.items()):
        if elem.type == "CBEAM":
            del bdf.elements[eid]
            bdf.add_cbar(eid, elem.pid, [elem.ga, elem.gb], list(elem.x), None)


def truth_start(analysis: Path, folder: Path) -> Path:
    """The truth's starting deck ``windy_bar.bdf`` in ``folder``: the analysis deck
    :func:`as_bars`."""
    bdf = read_pynastran(analysis)
    as_bars(bdf)
    path = Path(folder) / "windy_bar.bdf"
    bdf.write_bdf(str(path), enddata=True, size=16)
    return path


def sensors() -> list[tuple[int, int]]:
    """(grid, component) of the GVT: x, y and z at 40 free grids, evenly over the ids."""
    ids = np.array(sorted(g for g in read_pynastran(DECK).nodes
                          if g not in ROOT and g not in MASS_POINTS))
    grids = ids[np.linspace(0, ids.size - 1, N_GRIDS).round().astype(int)]
    return [(int(g), c) for g in grids for c in (1, 2, 3)]


def brace_grids() -> tuple[int, ...]:
    """The rib points: dependent grids of the deck's RBE2s but the hinge's, sorted."""
    bdf = read_pynastran(DECK)
    return tuple(sorted(int(g) for eid, r in bdf.rigid_elements.items()
                        if r.type == "RBE2" and eid != HINGE for g in r.Gmi))
