"""Generator of the X-56A-class flexible flying wing, the project's shipped example aircraft.

The aircraft is of the reference paper's kind (Pak & Truong, X-56A GVT-validated FE model,
``../shared/reference/x56a-model-tuning-paper.txt``): a tailless flying wing of 28 ft span with a
centre body (66 in chord on the centre line), wings swept 30 deg at the leading edge, winglets,
two turbojets on top of the centre body, a nose air-data boom, nose and main landing gear, water
ballast tanks in the wings and fuel in the centre body. It is a beam ("stick") model:

* units: inch, lbf, s. Masses are written as weights in lbm and turned into slinch
  (lbf s^2/in) by ``PARAM WTMASS 0.00259`` (1/386.1), as in US Nastran decks; inertias in lbm in^2.
  Axes: x aft from a datum 110 in ahead of the centre-body leading edge, y to starboard, z up.
* structure: CBAR/PBAR/MAT1 beams for the centre-body spine, the wing carry-through, the wings
  (elastic axis at 40 % chord, sections geometric from ``wing_root`` to ``wing_tip``), winglets,
  engine pylons, the nose boom and nose / main landing gear (uniform straight members). Rigid chords: every wing and
  winglet station has leading- and trailing-edge grids (the GVT's sensor sites and the splines'
  anchors) tied to the elastic-axis grid by RBE2; the engines hang on their pylons by RBE2 (the
  paper's rigid elements). All mass is CONM2 (MAT1 RHO = 0), so lumped and coupled mass agree and
  MYSTRAN (lumped only) runs the same deck. Free-free: no SPC.
* configurations: ``x56_efew.bdf`` (empty fuel, empty water: unusable residuals in the tanks) and
  ``x56_fffw.bdf`` (full fuel, full water); both INCLUDE ``structure_x56.inc`` (every structural
  property and the airframe masses), ``aero_x56.inc`` (CAERO1 / SPLINE1 / MKAERO1 / FLUTTER) and
  their own ``masses_efew.inc`` / ``masses_fffw.inc`` (the same CONM2 ids with the tank contents).
* aerodynamics: 2,000 doublet-lattice boxes on the centre body, wings and winglets (both sides,
  no symmetry), infinite-plate splines (SPLINE1) per panel, MKAERO1 at the paper's Mach 0.130,
  0.160, 0.195 and 0.284; one FLUTTER PKNL card per Mach (ids 1-4), matched points: altitude from
  ``ALTITUDES_M`` of the US76 atmosphere, density = rho(h) and V = M a(h). Structural damping
  g = 0.01 on every mode (SDAMP / TABDMP1).

API (import with ``data/x56_like`` on ``sys.path``; nothing in the packages imports this)::

    params = X56Parameters()                       # the analysis model (ANALYSIS)
    write_model(folder, params)                    # writes the two decks and their includes
    deck_texts(params) -> {file name: text}        # the same files as strings (byte-deterministic)
    mass_items(params, "efew") -> list[MassItem]   # every CONM2 for hand sums
    structure_bulk(params) -> list[str]            # structure cards only (for solver cross-checks)
    write_mode_table(folder, params)               # modes of both decks -> mode_table.md (named)

Hooks for a richer TRUTH model (``data/x56_like/truth/`` builds one with ``dataclasses.replace``):
``main_gear_taper`` (tip/root section size of the main-gear leg, with ``main_gear_segments``
segments of varying PBARs), ``main_gear_bow`` (lateral offset of the leg's middle, a curved leg),
``engine_mount`` (six CELAS2 stiffnesses between pylon and engine instead of the RBE2),
``cable_weight`` (GVT cables, distributed along both wings' elastic axes), ``suspension``
(bungees at the nose and mid-wings: CELAS2 springs of that vertical stiffness, lb/in, and
``SUSPENSION_PENDULUM`` times it horizontally, to SPC'd ground grids 60 in above) and
``property_factors`` / ``mass_factors`` (scatter: (PBAR id, field, factor) and (CONM2 id, factor)
applied when the cards are written). Ids: grids by component in ``COMPONENTS`` (left side +1000
for wing / winglet, +100 for engine and gear); PBAR 101 spine, 102 boom, 103 carry-through, 111-119
wing segments root to tip, 121 winglet, 132 pylon, 141 nose gear, 151.. main-gear segments, left
copies +100 (not for ``CENTRE_LINE_PROPERTIES``); CONM2 8xxx (left carry-through, wing, cables
and winglet +1000; left engine and gear +1), tanks 8901-8902 fuel, 8911-8923 water.

Run ``python data/x56_like/make_model.py`` to rewrite the committed files.
"""
from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))

from flutter.atmosphere import Units, atmosphere  # noqa: E402
from structures.bulk_text import card, real8  # noqa: E402
from structures.common.errors import InputError  # noqa: E402

#: PARAM WTMASS: lbm -> slinch (1 / 386.1 in/s^2).
WTMASS = 0.00259
#: The paper's Mach numbers (matched-point flutter, Table 6).
MACHS = (0.130, 0.160, 0.195, 0.284)
#: Reduced frequencies k = omega b / V, b = REFC / 2 (Nastran's convention).
REDUCED_FREQUENCIES = (0.001, 0.03, 0.07, 0.12, 0.2, 0.3, 0.45, 0.65, 0.9, 1.3, 1.8, 2.5)
#: Matched-point altitudes, m (US76), from high to low (density increasing).
ALTITUDES_M = tuple(float(h) for h in np.arange(20000.0, -1001.0, -500.0))
#: Reference chord (in) and sea-level density (slinch/in^3) of the AERO card.
REFC = 30.0
RHOREF = 1.146e-7             # 1.225 kg/m^3 in slinch/in^3, to the 4 digits of the field
#: Structural damping g on every mode (the paper's 1 %).
STRUCTURAL_G = 0.01
CONFIGURATIONS = ("efew", "fffw")
#: PBARs of members on the centre line or shared by both sides (spine and engine deck, boom, nose
#: gear); every other PBAR has a left-side copy with id + 100.
CENTRE_LINE_PROPERTIES = (101, 102, 141)
#: Truth hook: horizontal (pendulum) stiffness of a suspension point relative to its vertical one.
SUSPENSION_PENDULUM = 0.25

# planform (in): centre body to y = 30, wing to the tip at y = 166, winglet 24 in high
X_LE0, C0 = 110.0, 66.0                   # centre-body leading edge and chord on the centre line
Y_ROOT, C_ROOT, Y_TIP, C_TIP = 30.0, 40.0, 166.0, 18.0
SWEEP_LE = math.radians(30.0)
EA = 0.40                                 # elastic axis, fraction of chord
WING_Y = (30.0, 45.0, 60.0, 75.0, 90.0, 105.0, 120.0, 135.0, 150.0, 166.0)
WINGLET_Z, WINGLET_TIP_C, WINGLET_SWEEP = (0.0, 8.0, 16.0, 24.0), 10.0, math.radians(40.0)
SPINE_X = (110.0, 122.0, 134.0, 146.0, 158.0, 170.0, 182.0)
BOOM_X = (70.0, 90.0)

#: Grid-id ranges of the aircraft's components (right side; the left side of a winged component is
#: +1000, of the engine and gear +100). Used by the mode classification.
COMPONENTS = {"centre body": (1000, 1099), "boom": (1100, 1199), "carry-through": (2000, 2299),
              "wing": (3000, 3299), "winglet": (3300, 3599), "engine": (5000, 5299),
              "nose gear": (6000, 6099), "main gear": (6100, 6299)}


def component_of(grid: int) -> str:
    """Name of the component a grid id belongs to (``COMPONENTS``, both sides)."""
    g = grid - 1000 if 4000 <= grid < 4600 else grid
    for name, (lo, hi) in COMPONENTS.items():
        if lo <= g <= hi:
            return name
    return "ground"


@dataclass(frozen=True)
class Section:
    """PBAR section: area A (in^2), I1 (vertical / out-of-plane bending), I2, J (in^4)."""

    A: float
    I1: float
    I2: float
    J: float

    def __post_init__(self):
        bad = [f.name for f in fields(self) if not getattr(self, f.name) > 0]
        if bad:
            raise InputError(f"Section {self}: {bad} must be > 0. Fix: give positive properties.")

    def scaled(self, r: float) -> "Section":
        """The section of a member r times as large (area ~ r^2, inertias ~ r^4)."""
        return Section(self.A * r ** 2, self.I1 * r ** 4, self.I2 * r ** 4, self.J * r ** 4)

    def toward(self, other: "Section", t: float) -> "Section":
        """Geometric interpolation: self at t = 0, ``other`` at t = 1."""
        return Section(*(getattr(self, n) * (getattr(other, n) / getattr(self, n)) ** t
                         for n in ("A", "I1", "I2", "J")))


@dataclass(frozen=True)
class X56Parameters:
    """Every property and mass of the model (weights in lb, inertias in lb in^2, lengths in in).

    The defaults are the analysis model. Fields after ``ballast_full`` are the truth hooks (see the
    module docstring); their defaults leave the analysis model unchanged.
    """

    E: float = 1.0e7
    nu: float = 0.3
    spine: Section = Section(6.0, 60.0, 40.0, 60.0)
    carry_through: Section = Section(4.0, 8.0, 40.0, 6.0)
    wing_root: Section = Section(2.0, 0.62, 20.0, 0.30)
    wing_tip: Section = Section(0.4, 0.125, 2.0, 0.20)
    winglet: Section = Section(0.5, 0.8, 0.02, 0.05)
    engine_pylon: Section = Section(0.8, 0.035, 0.025, 0.05)
    boom: Section = Section(0.3, 0.047, 0.047, 0.06)
    nose_gear: Section = Section(0.5, 0.025, 0.012, 0.03)
    main_gear: Section = Section(0.5, 0.13, 0.020, 0.03)
    spine_weights: tuple = (14.0, 22.0, 24.0, 24.0, 22.0, 16.0, 12.0)
    carry_weight: float = 6.0
    wing_weight: float = 24.0                       # one wing, spread over the stations ~ chord^2
    winglet_weight: float = 1.0
    engine_weight: float = 12.0
    boom_weights: tuple = (0.8, 0.6)                # tip, middle
    nose_gear_weights: tuple = (1.0, 1.6)           # middle, wheel
    main_gear_weights: tuple = (1.5, 2.8)           # middle, wheel
    fuel_full: float = 30.0                         # each of two centre-body tanks
    fuel_residual: float = 1.0
    ballast_full: float = 30.0                      # each of three tanks per wing
    ballast_residual: float = 0.5
    main_gear_segments: int = 2
    main_gear_taper: float = 1.0
    main_gear_bow: float = 0.0
    engine_mount: tuple | None = None
    cable_weight: float = 0.0
    suspension: float | None = None
    property_factors: tuple = field(default=())
    mass_factors: tuple = field(default=())

    def __post_init__(self):
        if not (self.E > 0 and 0 <= self.nu < 0.5):
            raise InputError(f"X56Parameters: E = {self.E}, nu = {self.nu}. Fix: E > 0, 0 <= nu < 0.5.")
        if self.main_gear_segments < 1 or self.main_gear_taper <= 0:
            raise InputError("X56Parameters: main_gear_segments >= 1 and main_gear_taper > 0. "
                             "Fix: correct them.")
        if self.engine_mount is not None and (len(self.engine_mount) != 6
                                              or min(self.engine_mount) <= 0):
            raise InputError("X56Parameters: engine_mount needs six positive stiffnesses (T1..R3). "
                             "Fix: give six values or None (rigid RBE2).")
        weights = [self.carry_weight, self.wing_weight, self.winglet_weight, self.engine_weight,
                   self.fuel_full, self.ballast_full, *self.spine_weights, *self.boom_weights,
                   *self.nose_gear_weights, *self.main_gear_weights]
        if min(weights) <= 0 or self.fuel_residual < 0 or self.ballast_residual < 0 \
                or self.cable_weight < 0:
            raise InputError("X56Parameters: weights must be positive (residuals, cables >= 0). "
                             "Fix: correct the weights.")


ANALYSIS = X56Parameters()


@dataclass(frozen=True)
class MassItem:
    """One CONM2: id, grid, weight (lb), offset from the grid (in), I11, I22, I33 (lb in^2)."""

    eid: int
    grid: int
    weight: float
    offset: tuple
    inertia: tuple
    name: str

    def __post_init__(self):
        # the values exactly as the 8-character CONM2 fields hold them, so sums agree with the deck
        object.__setattr__(self, "weight", _field_value(self.weight))
        object.__setattr__(self, "offset", tuple(_field_value(v) for v in self.offset))
        object.__setattr__(self, "inertia", tuple(_field_value(v) for v in self.inertia))


def _field_value(value: float) -> float:
    """A real as written to (and read back from) an 8-character field."""
    return float(real8(float(value)).replace("E", "e"))


def leading_edge(y: float) -> float:
    """x of the leading edge at span station y (in): swept SWEEP_LE from the centre line."""
    return X_LE0 + abs(y) * math.tan(SWEEP_LE)


def chord(y: float) -> float:
    """Local chord (in): linear on the centre body (66 -> 40 in) and on the wing (40 -> 18 in)."""
    y = abs(y)
    if y <= Y_ROOT:
        return C0 + (C_ROOT - C0) * y / Y_ROOT
    return C_ROOT + (C_TIP - C_ROOT) * (y - Y_ROOT) / (Y_TIP - Y_ROOT)


def _grids(params: X56Parameters) -> dict[int, tuple]:
    """Every grid id -> (x, y, z) as written to the GRID cards."""
    return {gid: tuple(_field_value(v) for v in xyz) for gid, xyz in _grid_layout(params).items()}


def _grid_layout(params: X56Parameters) -> dict[int, tuple]:
    """Every grid id -> (x, y, z), right then left side."""
    g = {1001 + i: (x, 0.0, 0.0) for i, x in enumerate(SPINE_X)}
    g.update({1101 + i: (x, 0.0, 0.0) for i, x in enumerate(BOOM_X)})
    for side, s in ((0, 1.0), (1000, -1.0)):
        g[2001 + side // 10] = (146.0, s * 15.0, 0.0)                  # carry-through middle
        for i, y in enumerate(WING_Y):
            le, c = leading_edge(y), chord(y)
            g[3001 + side + i] = (le + EA * c, s * y, 0.0)
            g[3101 + side + i] = (le + 0.05 * c, s * y, 0.0)
            g[3201 + side + i] = (le + 0.95 * c, s * y, 0.0)
        le_tip = leading_edge(Y_TIP)
        for i, z in enumerate(WINGLET_Z[1:]):
            le = le_tip + z * math.tan(WINGLET_SWEEP)
            c = C_TIP + (WINGLET_TIP_C - C_TIP) * z / WINGLET_Z[-1]
            g[3301 + side + i] = (le + EA * c, s * Y_TIP, z)
            g[3401 + side + i] = (le + 0.05 * c, s * Y_TIP, z)
            g[3501 + side + i] = (le + 0.95 * c, s * Y_TIP, z)
    for side, s in ((0, 1.0), (100, -1.0)):
        g[5001 + side] = (170.0, s * 9.0, 0.0)                         # engine deck, pylon root
        g[5011 + side] = (170.0, s * 9.0, 6.0)                         # pylon top (mount)
        g[5021 + side] = (174.0, s * 9.0, 10.0)                        # engine CG
        if params.engine_mount is not None:
            g[5031 + side] = (170.0, s * 9.0, 6.0)                     # engine side of the mount
        n = params.main_gear_segments
        for i in range(n + 1):
            t = i / n
            bow = params.main_gear_bow * math.sin(math.pi * t)
            g[6101 + side + i] = (155.0 + 3.0 * t, s * (20.0 + 6.0 * t + bow), 0.0 - 20.0 * t)
    g.update({6001: (122.0, 0.0, -9.0), 6002: (122.0, 0.0, -18.0)})
    if params.suspension is not None:
        for i, gid in enumerate((1002, 3005, 4005)):
            x, y, z = g[gid]
            g[9001 + i] = (x, y, z + 60.0)
    return g


def _pbar(pid: int, sec: Section, factors: dict) -> str:
    vals = {name: getattr(sec, name) * factors.get((pid, name), 1.0) for name in ("A", "I1", "I2", "J")}
    return card("PBAR", pid, 1, vals["A"], vals["I1"], vals["I2"], vals["J"])


def _wing_sections(params: X56Parameters) -> list[Section]:
    """Section of each wing segment, geometric between root and tip in the segment's mid-span."""
    mid = [0.5 * (a + b) for a, b in zip(WING_Y[:-1], WING_Y[1:])]
    return [params.wing_root.toward(params.wing_tip, (y - Y_ROOT) / (Y_TIP - Y_ROOT)) for y in mid]


def structure_bulk(params: X56Parameters = ANALYSIS) -> list[str]:
    """Structure cards: PARAM, MAT1, GRID, CBAR/PBAR, RBE2 (CELAS2, SPC1 for truth hooks), the
    airframe CONM2s. Both solvers read them."""
    fac = {(int(p), str(n)): float(f) for p, n, f in params.property_factors}
    g = _grids(params)
    out = ["$ X-56A-class flying wing, structure (in, lbf, s; weights in lbm, PARAM WTMASS)",
           card("PARAM", "WTMASS", WTMASS), card("MAT1", 1, params.E, None, params.nu, 0.0)]
    out += [card("GRID", gid, None, *xyz) for gid, xyz in sorted(g.items())]
    props = [(101, params.spine), (102, params.boom), (103, params.carry_through),
             (121, params.winglet), (132, params.engine_pylon), (141, params.nose_gear)]
    props += [(111 + i, s) for i, s in enumerate(_wing_sections(params))]
    n = params.main_gear_segments
    for i in range(n):
        r = 1.0 + (params.main_gear_taper - 1.0) * (i + 0.5) / n
        props.append((151 + i, params.main_gear.scaled(r)))
    props += [(pid + 100, sec) for pid, sec in props    # left side: ids + 100 (linked in tuning)
              if pid not in CENTRE_LINE_PROPERTIES]
    out += [_pbar(pid, sec, fac) for pid, sec in sorted(props)]
    up, fore = (0.0, 0.0, 1.0), (1.0, 0.0, 0.0)      # orientation vectors: I1 vertical / fore-aft
    line = [1101, 1102] + [1001 + i for i in range(len(SPINE_X))]
    bars = [(1001 + i, 102 if a > 1100 else 101, a, b, up)          # (eid, pid, ga, gb, v)
            for i, (a, b) in enumerate(zip(line[:-1], line[1:]))]
    for k in (0, 1):
        side, pside = 1000 * k, 100 * k
        bars += [(2001 + pside, 103 + pside, 1004, 2001 + pside, up),
                 (2002 + pside, 103 + pside, 2001 + pside, 3001 + side, up)]
        bars += [(3001 + side + i, 111 + i + pside, 3001 + side + i, 3002 + side + i, up)
                 for i in range(len(WING_Y) - 1)]
        winglet = [3001 + side + len(WING_Y) - 1] + [3301 + side + i for i in range(3)]
        bars += [(3301 + side + i, 121 + pside, a, b, fore)
                 for i, (a, b) in enumerate(zip(winglet[:-1], winglet[1:]))]
        side = 100 * k
        bars += [(5001 + side, 101, 1006, 5001 + side, up),                    # engine deck
                 (5002 + side, 132 + pside, 5001 + side, 5011 + side, fore)]    # pylon
        bars.append((6100 + side, 103 + pside, 2001 + side, 6101 + side, up))   # gear bay
        bars += [(6101 + side + i, 151 + i + pside, 6101 + side + i, 6102 + side + i, fore)
                 for i in range(n)]
    bars += [(6001, 141, 1002, 6001, fore), (6002, 141, 6001, 6002, fore)]
    out += [card("CBAR", eid, pid, ga, gb, *v) for eid, pid, ga, gb, v in sorted(bars)]
    out += _joints(params, g)
    out += [_conm2(m, params) for m in airframe_masses(params)]
    return out


def _joints(params: X56Parameters, g: dict) -> list[str]:
    """Rigid chords (RBE2), engine attachment (RBE2 or CELAS2 springs), suspension."""
    out = []
    for side in (0, 1000):
        for i in range(len(WING_Y)):
            out.append(card("RBE2", 7001 + side + i, 3001 + side + i, 123456, 3101 + side + i,
                            3201 + side + i))
        for i in range(3):
            out.append(card("RBE2", 7101 + side + i, 3301 + side + i, 123456, 3401 + side + i,
                            3501 + side + i))
    for side in (0, 100):
        if params.engine_mount is None:
            out.append(card("RBE2", 7501 + side, 5011 + side, 123456, 5021 + side))
            continue
        out.append(card("RBE2", 7501 + side, 5031 + side, 123456, 5021 + side))
        out += [card("CELAS2", 7511 + side + c, k, 5011 + side, c + 1, 5031 + side, c + 1)
                for c, k in enumerate(params.engine_mount)]
    if params.suspension is not None:
        for i, gid in enumerate((1002, 3005, 4005)):       # bungee: vertical + pendulum springs
            out += [card("CELAS2", 9101 + 10 * i + c, params.suspension * (1.0 if c == 3 else
                                                                           SUSPENSION_PENDULUM),
                         9001 + i, c, gid, c) for c in (1, 2, 3)]
        out.append(card("SPC1", 1, 123456, 9001, "THRU", 9003))
    return out


def _conm2(m: MassItem, params: X56Parameters) -> str:
    f = dict((int(e), float(v)) for e, v in params.mass_factors).get(m.eid, 1.0)
    return card("CONM2", m.eid, m.grid, 0, m.weight * f, *m.offset, None,
                m.inertia[0] * f, 0.0, m.inertia[1] * f, 0.0, 0.0, m.inertia[2] * f)


def _box_inertia(w: float, lx: float, ly: float, lz: float) -> tuple:
    """I11, I22, I33 of a uniform box of weight w and edges lx, ly, lz about its centre."""
    return (w * (ly ** 2 + lz ** 2) / 12, w * (lx ** 2 + lz ** 2) / 12, w * (lx ** 2 + ly ** 2) / 12)


def airframe_masses(params: X56Parameters = ANALYSIS) -> list[MassItem]:
    """The CONM2s common to both configurations (everything but the tank contents)."""
    out = [MassItem(8001 + i, 1001 + i, w, (0.0, 0.0, 0.0), _box_inertia(w, 12.0, 24.0, 10.0),
                    "centre body") for i, w in enumerate(params.spine_weights)]
    out += [MassItem(8101 + i, 1101 + i, w, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), "nose boom")
            for i, w in enumerate(params.boom_weights)]
    chords2 = np.array([chord(y) ** 2 for y in WING_Y])
    share = params.wing_weight * chords2 / chords2.sum()
    wl_share = params.winglet_weight / 3
    cable = params.cable_weight / (2 * (len(WING_Y) - 1))
    for side, s in ((0, 1.0), (1000, -1.0)):
        out.append(MassItem(8201 + side, 2001 + side // 10, params.carry_weight, (0.0, 0.0, 0.0),
                            _box_inertia(params.carry_weight, 30.0, 15.0, 6.0), "carry-through"))
        for i, y in enumerate(WING_Y):
            c = chord(y)
            out.append(MassItem(8301 + side + i, 3001 + side + i, float(share[i]),
                                (0.05 * c, 0.0, 0.0), _box_inertia(float(share[i]), 1.0 * c,
                                                                   15.0, 0.1 * c), "wing"))
            if cable and i:
                out.append(MassItem(8401 + side + i, 3001 + side + i, cable, (0.0, 0.0, 0.0),
                                    (0.0, 0.0, 0.0), "GVT cables"))
        for i in range(3):
            out.append(MassItem(8501 + side + i, 3301 + side + i, wl_share, (0.0, 0.0, 0.0),
                                _box_inertia(wl_share, 8.0, 0.5, 8.0), "winglet"))
    n = params.main_gear_segments
    for k in (0, 1):
        side = 100 * k
        out.append(MassItem(8601 + k, 5021 + side, params.engine_weight, (0.0, 0.0, 0.0),
                            _box_inertia(params.engine_weight, 22.0, 6.0, 6.0), "engine"))
        out.append(MassItem(8701 + k, 6101 + side + max(n // 2, 1) - (n == 1),
                            params.main_gear_weights[0], (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                            "main gear"))
        out.append(MassItem(8711 + k, 6101 + side + n, params.main_gear_weights[1],
                            (0.0, 0.0, 0.0), _box_inertia(params.main_gear_weights[1], 8.0, 3.0,
                                                          8.0), "main gear"))
    out += [MassItem(8801, 6001, params.nose_gear_weights[0], (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                     "nose gear"),
            MassItem(8802, 6002, params.nose_gear_weights[1], (0.0, 0.0, 0.0),
                     _box_inertia(params.nose_gear_weights[1], 6.0, 2.0, 6.0), "nose gear")]
    return out


def tank_masses(params: X56Parameters, configuration: str) -> list[MassItem]:
    """Tank contents of a configuration: two centre-body fuel tanks, three ballast tanks per wing
    (at 30 % chord of stations 3-5). Same CONM2 ids in both configurations."""
    if configuration not in CONFIGURATIONS:
        raise InputError(f"configuration {configuration!r}; valid: {list(CONFIGURATIONS)}.")
    full = configuration == "fffw"
    fuel = params.fuel_full if full else params.fuel_residual
    water = params.ballast_full if full else params.ballast_residual
    out = [MassItem(8901 + i, gid, fuel, (0.0, 0.0, 0.0), _box_inertia(fuel, 12.0, 20.0, 8.0),
                    "fuel") for i, gid in enumerate((1004, 1005))]
    for side, i0 in ((0, 8911), (1000, 8921)):
        for j, i in enumerate((2, 3, 4)):
            c = chord(WING_Y[i])
            out.append(MassItem(i0 + j, 3001 + side + i, water, (-0.10 * c, 0.0, 0.0),
                                _box_inertia(water, 0.4 * c, 14.0, 0.08 * c), "water ballast"))
    return out


def mass_items(params: X56Parameters, configuration: str) -> list[MassItem]:
    """Every CONM2 of a configuration (airframe + tanks)."""
    return airframe_masses(params) + tank_masses(params, configuration)


def _panel(eid: int, p1, c1: float, p4, c4: float, nspan: int, nchord: int) -> str:
    return card("CAERO1", eid, 1, 0, nspan, nchord, None, None, 1, *p1, c1, *p4, c4)


def aero_bulk(params: X56Parameters = ANALYSIS) -> list[str]:
    """AERO, PAERO1, CAERO1 (2,000 boxes), SET1 / SPLINE1, MKAERO1, FLFACT / FLUTTER, TABDMP1."""
    units = Units.named("english_in")
    out = ["$ aerodynamics: doublet lattice, 2000 boxes; k = omega b / V with b = REFC / 2",
           card("AERO", 0, None, REFC, RHOREF), card("PAERO1", 1)]
    x_root = leading_edge(Y_ROOT)
    x_tip = leading_edge(Y_TIP)
    wl_le = x_tip + WINGLET_Z[-1] * math.tan(WINGLET_SWEEP)
    spanwise = {"centre": (10, 24), "wing": (40, 16), "winglet": (10, 12)}
    panels = []                                             # (eid, p1, c1, p4, c4, kind, grids)
    for k, s in ((0, 1.0), (1, -1.0)):
        side = 1000 * k
        cb = [1001 + i for i in range(len(SPINE_X))] + [2001 + 100 * k, 3001 + side, 3101 + side,
                                                         3201 + side]
        wing = [g + side + i for g in (3001, 3101, 3201) for i in range(len(WING_Y))]
        wl = [3010 + side, 3110 + side, 3210 + side] + [g + side + i for g in (3301, 3401, 3501)
                                                        for i in range(3)]
        panels += [(100000 + 10000 * k, (X_LE0, 0.0, 0.0), C0, (x_root, s * Y_ROOT, 0.0), C_ROOT,
                    "centre", cb),
                   (120000 + 10000 * k, (x_root, s * Y_ROOT, 0.0), C_ROOT,
                    (x_tip, s * Y_TIP, 0.0), C_TIP, "wing", wing),
                   (140000 + 10000 * k, (x_tip, s * Y_TIP, 0.0), C_TIP,
                    (wl_le, s * Y_TIP, WINGLET_Z[-1]), WINGLET_TIP_C, "winglet", wl)]
    for eid, p1, c1, p4, c4, kind, grids in panels:
        ns, nc = spanwise[kind]
        if p4[1] < p1[1]:                    # left side: corner 1 outboard, so the normal is +z
            p1, c1, p4, c4 = p4, c4, p1, c1
        out.append(_panel(eid, p1, c1, p4, c4, ns, nc))
        out.append(card("SET1", eid, *sorted(grids)))
        out.append(card("SPLINE1", eid, eid, eid, eid + ns * nc - 1, eid, 0.0))
    for ks in (REDUCED_FREQUENCIES[:8], REDUCED_FREQUENCIES[8:]):
        out.append(card("MKAERO1", *MACHS, *[None] * (8 - len(MACHS)), *ks))
    atm = atmosphere(np.array(ALTITUDES_M))
    rho = atm["density"] / units.density / RHOREF
    out.append(card("FLFACT", 1, *[float(f"{r:.5g}") for r in rho]))
    for i, mach in enumerate(MACHS):
        v = mach * atm["speed_of_sound"] / units.length
        out.append(card("FLFACT", 10 + i + 1, *[mach] * len(ALTITUDES_M)))
        out.append(card("FLFACT", 20 + i + 1, *[float(f"{x:.6g}") for x in v]))
        out.append(card("FLUTTER", i + 1, "PKNL", 1, 10 + i + 1, 20 + i + 1, "L", None,
                        1.0e-3))
    out.append(card("TABDMP1", 10, "G", None, None, None, None, None, None,
                    0.0, STRUCTURAL_G, 1000.0, STRUCTURAL_G, "ENDT"))
    return out


def masses_bulk(params: X56Parameters, configuration: str) -> list[str]:
    """The configuration's tank CONM2s."""
    title = {"efew": "empty fuel, empty water (unusable residuals)",
             "fffw": "full fuel, full water"}[configuration]
    return [f"$ X-56A-class flying wing, tank contents: {title}"] + [
        _conm2(m, params) for m in tank_masses(params, configuration)]


def _deck(configuration: str) -> str:
    name = configuration.upper()
    lines = [f"$ X-56A-class flexible flying wing, {name} (data/x56_like/make_model.py)",
             "$ units: in, lbf, s; CONM2 weights in lbm with PARAM WTMASS 0.00259 (slinch)",
             "SOL 145", "CEND", f"TITLE = X56-LIKE {name}", "ECHO = NONE", "METHOD = 1",
             "SDAMP = 10", "DISP(PLOT) = ALL", "BEGIN BULK", "INCLUDE 'structure_x56.inc'",
             f"INCLUDE 'masses_{configuration}.inc'", "INCLUDE 'aero_x56.inc'",
             card("EIGRL", 1, None, None, 34), "ENDDATA"]
    return "\n".join(lines) + "\n"


def deck_texts(params: X56Parameters = ANALYSIS) -> dict[str, str]:
    """Every file of the model as text: the two decks and their four includes."""
    texts = {"structure_x56.inc": "\n".join(structure_bulk(params)) + "\n",
             "aero_x56.inc": "\n".join(aero_bulk(params)) + "\n"}
    for c in CONFIGURATIONS:
        texts[f"masses_{c}.inc"] = "\n".join(masses_bulk(params, c)) + "\n"
        texts[f"x56_{c}.bdf"] = _deck(c)
    return texts


def write_model(folder, params: X56Parameters = ANALYSIS) -> dict[str, Path]:
    """Write the model's files into ``folder``; returns {file name: path}."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    out = {}
    for name, text in deck_texts(params).items():
        path = folder / name
        path.write_bytes(text.encode("ascii"))
        out[name] = path
    return out


def write_mode_table(folder, params: X56Parameters = ANALYSIS) -> Path:
    """Compute both configurations' modes (our solver, lumped mass = the deck's CONM2s) from the
    decks in ``folder``, name them (mode_names.classify_modes) and write ``mode_table.md``."""
    from mode_names import classify_modes, mode_table_markdown
    from structures.bdf import read_model
    from structures.modal import compute_modes

    folder = Path(folder)
    tables = {c: classify_modes(compute_modes(read_model(folder / f"x56_{c}.bdf")), c, params)
              for c in CONFIGURATIONS}
    path = folder / "mode_table.md"
    text = ("# Modes of the X-56A-class model (data/x56_like/make_model.py)\n\n"
            "Our solver on `x56_efew.bdf` / `x56_fffw.bdf` (EIGRL ND = 34); names from the shapes "
            "(`mode_names.py`: symmetry, component holding most kinetic energy and its share, "
            "dominant motion).\n\n" + mode_table_markdown(tables))
    path.write_bytes(text.encode("ascii"))
    return path


def main(argv: list[str]) -> None:
    """``python make_model.py [FOLDER]``: write the model (default: beside this script)."""
    folder = Path(argv[0]) if argv else HERE
    for path in write_model(folder).values():
        print(f"wrote {path}")
    print(f"wrote {write_mode_table(folder)}")


if __name__ == "__main__":
    main(sys.argv[1:])
