"""Generator of a small swept flying wing with symmetric body-freedom flutter (SBFF), issue 13.

The aircraft is this project's own: a tailless flying wing of 5.5 m span, leading edge swept
30 deg, chord 0.9 m on the centre line tapering to 0.36 m at the tip (aspect ratio 8.7), with a
centre body that is a single lumped mass (the payload / ballast). Its short period is slow because
the static margin is small and the pitch inertia large, and it rises with speed until it meets the
first symmetric wing bending: body-freedom flutter, the mechanism of Weisshaar & Zeiler
(J. Aircraft 20(12), 1983) and of the BFF example of Chen's g-method paper (AIAA J. 38(9), 2000).

* units: SI (m, kg, s, N). Axes: x aft from the centre-line leading edge, y to starboard, z up.
* symmetric half model (the starboard wing, y >= 0): AERO SYMXZ = +1 mirrors the aerodynamics;
  the centre-line grid is constrained in the antisymmetric and in-plane components (SPC1 1246:
  surge, side-slip, roll and yaw), so the aircraft is free in plunge (T3) and pitch (R5) only and
  has two rigid-body modes. All masses are halves of the aircraft's.
* structure: a CBAR spar on the elastic axis (``EA`` of the chord) from the centre line to the
  tip in ``N_STATIONS - 1`` segments, bending and torsion stiffness interpolated geometrically
  from root to tip; a leading-edge and a trailing-edge grid at every station, tied to the spar
  grid by RBE2 (rigid chords: the spline's anchors); all mass is CONM2 (MAT1 RHO = 0): the wing's
  on the leading- and trailing-edge grids (split so the section CG is at ``WING_CG`` of the
  chord), the centre body's on the centre-line spar grid with an x offset that places it at
  ``BFFParameters.body_x`` and its own pitch inertia ``BFFParameters.body_pitch_inertia`` (I22).
  Only cards MYSTRAN also runs (CBAR, RBE2, CONM2 with offsets, SPC1, EIGRL).
* aerodynamics: one CAERO1 of ``NSPAN x NCHORD`` doublet-lattice boxes over the half wing,
  SPLINE1 (infinite plate) on every spar, leading- and trailing-edge grid; MKAERO1 at Mach
  ``MACH`` and the reduced frequencies ``REDUCED_FREQUENCIES`` (k = omega b / V, b = REFC / 2;
  dense at low k, where the short period lives); FLUTTER 1 PK at sea level (RHOREF 1.225 kg/m^3,
  density ratio 1) over ``VELOCITIES``.

API (import with ``data/bff_wing`` on ``sys.path``; nothing in the packages imports this)::

    params = BFFParameters(body_x=0.80, body_pitch_inertia=1.5)
    deck_text(params) -> str               # the whole deck (byte-deterministic)
    write_deck(path, params)               # writes it
    structure_bulk(params) -> list[str]    # structure and mass cards only (MYSTRAN cross-check)
    mass_items(params) -> list[MassItem]   # every CONM2 (for hand sums of weight and CG)

Run ``python data/bff_wing/make_deck.py [PATH]`` to rewrite the committed ``bff_wing.bdf``.
"""
from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))

from structures.bulk_text import card  # noqa: E402
from structures.common.errors import InputError  # noqa: E402

# planform (m)
C_ROOT, C_TIP, HALF_SPAN = 0.90, 0.36, 2.75
SWEEP_LE = math.radians(30.0)
#: Elastic axis and section CG of the wing, fractions of the chord from the leading edge.
EA, WING_CG = 0.40, 0.42
#: Chordwise positions of the leading- and trailing-edge mass / spline grids (fractions of chord).
X_FRONT, X_REAR = 0.10, 0.70
N_STATIONS = 12
#: Reference chord (m, ~ the mean aerodynamic chord) and sea-level density (kg/m^3).
REFC = 0.67
RHOREF = 1.225
MACH = 0.2
#: Reduced frequencies k = omega b / V, b = REFC / 2 (dense at low k for the short period).
REDUCED_FREQUENCIES = (0.001, 0.005, 0.01, 0.02, 0.03, 0.045, 0.06, 0.08, 0.1, 0.13, 0.17, 0.22,
                       0.3, 0.4, 0.55, 0.75, 1.0, 1.5)
#: True airspeeds of the FLUTTER card (m/s).
VELOCITIES = tuple(float(v) for v in np.arange(10.0, 150.1, 2.5))
#: Doublet-lattice boxes of the half wing.
NSPAN, NCHORD = 20, 10
E_MOD, NU = 70.0e9, 0.3
#: Modes of the EIGRL card (2 rigid + 8 elastic).
NMODES = 10


def leading_edge(y: float) -> float:
    """x of the leading edge at span station y (m)."""
    return y * math.tan(SWEEP_LE)


def chord(y: float) -> float:
    """Chord at span station y (linear taper, m)."""
    return C_ROOT + (C_TIP - C_ROOT) * y / HALF_SPAN


@dataclass(frozen=True)
class MassItem:
    """One CONM2: id, grid, mass (kg), offset from the grid (m), inertia I11, I22, I33 (kg m^2)."""

    eid: int
    grid: int
    mass: float
    offset: tuple = (0.0, 0.0, 0.0)
    inertia: tuple = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class BFFParameters:
    """Every property and mass of the half model (SI).

    ``body_x`` (m, aft of the centre-line leading edge) and ``body_pitch_inertia`` (kg m^2, about
    the body's own CG; half the aircraft's) are the study's variables: the CG and the pitch inertia.
    Stiffnesses are of the spar at the root and the tip (geometric interpolation between).
    """

    body_x: float = 0.70
    body_pitch_inertia: float = 1.5
    body_mass: float = 12.0              # half of the centre body
    wing_mass: float = 8.0               # one wing, spread over the stations ~ chord
    EI_root: float = 8.0e3               # out-of-plane bending, N m^2
    EI_tip: float = 6.0e2
    GJ_root: float = 1.2e4               # torsion, N m^2
    GJ_tip: float = 1.5e3
    in_plane: float = 20.0               # in-plane over out-of-plane bending stiffness

    def __post_init__(self):
        bad = [n for n in ("body_pitch_inertia", "body_mass", "wing_mass", "EI_root", "EI_tip",
                           "GJ_root", "GJ_tip", "in_plane") if not getattr(self, n) > 0]
        if bad:
            raise InputError(f"BFFParameters: {bad} must be > 0. Fix: give positive values.")
        if not 0.0 <= self.body_x <= C_ROOT + HALF_SPAN * math.tan(SWEEP_LE):
            raise InputError(f"BFFParameters: body_x = {self.body_x} m lies outside the aircraft "
                             "(0 .. trailing edge of the tip). Fix: give an x on the airframe.")


ANALYSIS = BFFParameters()


def _stations() -> np.ndarray:
    return np.linspace(0.0, HALF_SPAN, N_STATIONS)


def grids() -> dict[int, tuple]:
    """Grid id -> (x, y, z): spar 1.., leading-edge 101.., trailing-edge 201.. (station order)."""
    out = {}
    for i, y in enumerate(_stations()):
        x0, c = leading_edge(y), chord(y)
        out[1 + i] = (x0 + EA * c, y, 0.0)
        out[101 + i] = (x0 + X_FRONT * c, y, 0.0)
        out[201 + i] = (x0 + X_REAR * c, y, 0.0)
    return out


def mass_items(params: BFFParameters = ANALYSIS) -> list[MassItem]:
    """The wing's CONM2s (front / rear grids, section CG at ``WING_CG``) and the centre body's."""
    y = _stations()
    dy = np.gradient(y)                               # tributary span of each station
    share = np.array([chord(v) for v in y]) * dy
    station_mass = params.wing_mass * share / share.sum()
    rear = (WING_CG - X_FRONT) / (X_REAR - X_FRONT)   # mass fraction on the rear grid
    items = []
    for i, m in enumerate(station_mass):
        items.append(MassItem(301 + i, 101 + i, float(m * (1 - rear))))
        items.append(MassItem(401 + i, 201 + i, float(m * rear)))
    x_spar = grids()[1][0]
    items.append(MassItem(500, 1, params.body_mass, (params.body_x - x_spar, 0.0, 0.0),
                          (0.2 * params.body_pitch_inertia, params.body_pitch_inertia,
                           1.2 * params.body_pitch_inertia)))
    return items


def _conm2(m: MassItem) -> str:
    return card("CONM2", m.eid, m.grid, 0, float(f"{m.mass:.6g}"),
                *[float(f"{v:.6g}") for v in m.offset], None,
                float(f"{m.inertia[0]:.6g}"), 0.0, float(f"{m.inertia[1]:.6g}"), 0.0, 0.0,
                float(f"{m.inertia[2]:.6g}"))


def structure_bulk(params: BFFParameters = ANALYSIS) -> list[str]:
    """GRID, CBAR / PBAR / MAT1, RBE2, CONM2 and SPC1 cards of the half model."""
    g = grids()
    out = ["$ structure: spar on the elastic axis, rigid chords, lumped masses (SI)",
           card("MAT1", 1, E_MOD, None, NU, 0.0)]
    out += [card("GRID", gid, None, *[float(f"{v:.6g}") for v in xyz]) for gid, xyz in g.items()]
    g_mod = E_MOD / (2 * (1 + NU))
    for i in range(N_STATIONS - 1):
        t = (i + 0.5) / (N_STATIONS - 1)
        EI = params.EI_root * (params.EI_tip / params.EI_root) ** t
        GJ = params.GJ_root * (params.GJ_tip / params.GJ_root) ** t
        area = 1.0e-4 * (1 - 0.6 * t)                  # axial stiffness plays no part here
        out.append(card("PBAR", 11 + i, 1, float(f"{area:.4g}"), float(f"{EI / E_MOD:.5g}"),
                        float(f"{params.in_plane * EI / E_MOD:.5g}"),
                        float(f"{GJ / g_mod:.5g}"), 0.0))
        out.append(card("CBAR", 11 + i, 11 + i, 1 + i, 2 + i, 0.0, 0.0, 1.0))
    out += [card("RBE2", 601 + i, 1 + i, 123456, 101 + i, 201 + i) for i in range(N_STATIONS)]
    out += [_conm2(m) for m in mass_items(params)]
    out.append("$ symmetric half model: free in plunge (T3) and pitch (R5) only")
    out.append(card("SPC1", 1, 1246, 1))
    return out


def aero_bulk() -> list[str]:
    """AERO (SYMXZ = +1), PAERO1, CAERO1, SET1 / SPLINE1, MKAERO1, FLFACT / FLUTTER."""
    ends = (leading_edge(0.0), 0.0, 0.0), (leading_edge(HALF_SPAN), HALF_SPAN, 0.0)
    out = ["$ aerodynamics: doublet lattice, half wing mirrored (SYMXZ = +1); "
           "k = omega b / V with b = REFC / 2",
           card("AERO", 0, None, REFC, RHOREF, 1), card("PAERO1", 1),
           card("CAERO1", 1001, 1, 0, NSPAN, NCHORD, None, None, 1,
                *ends[0], C_ROOT, *[float(f"{v:.6g}") for v in ends[1]], C_TIP),
           card("SET1", 1001, *sorted(grids())),
           card("SPLINE1", 1001, 1001, 1001, 1000 + NSPAN * NCHORD, 1001, 0.0)]
    ks = REDUCED_FREQUENCIES
    for chunk in range(0, len(ks), 8):
        out.append(card("MKAERO1", MACH, *[None] * 7, *ks[chunk:chunk + 8]))
    out += [card("FLFACT", 1, 1.0), card("FLFACT", 2, MACH), card("FLFACT", 3, *VELOCITIES),
            card("FLUTTER", 1, "PK", 1, 2, 3, "L", None, 1.0e-4)]
    return out


def deck_text(params: BFFParameters = ANALYSIS) -> str:
    """The SOL 145 deck (executive, case control, bulk data) as text."""
    lines = ["$ BFF flying wing, symmetric half model (data/bff_wing/make_deck.py)",
             f"$ body_x = {params.body_x:g} m, body_pitch_inertia = {params.body_pitch_inertia:g} "
             "kg m^2 (half aircraft); units m, kg, s",
             "SOL 145", "CEND", "TITLE = BFF FLYING WING", "ECHO = NONE", "SPC = 1",
             "METHOD = 1", "FMETHOD = 1", "BEGIN BULK", *structure_bulk(params), *aero_bulk(),
             card("EIGRL", 1, None, None, NMODES), "ENDDATA"]
    return "\n".join(lines) + "\n"


def write_deck(path, params: BFFParameters = ANALYSIS) -> Path:
    """Write the deck to ``path``; returns it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(deck_text(params).encode("ascii"))
    return path


def main(argv: list[str]) -> None:
    """``python make_deck.py [PATH]``: write the deck (default ``bff_wing.bdf`` beside this)."""
    print(f"wrote {write_deck(Path(argv[0]) if argv else HERE / 'bff_wing.bdf')}")


if __name__ == "__main__":
    main(sys.argv[1:])
