"""U.S. Standard Atmosphere 1976 (= ISA below 32 km) and airspeed conversions.

Reference: U.S. Standard Atmosphere, 1976 (NOAA-S/T 76-1562), Table 4 (layer base geopotential
heights and lapse rates), eqs. 18 (geopotential height), 23a/23b (pressure in gradient/isothermal
layers), 42 (density), 50 (speed of sound). Valid from -5 km to 84.852 km geopotential.
The atmosphere is in SI; :class:`Units` converts to and from the model's consistent units.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from structures.common.errors import InputError

G0 = 9.80665                  # m/s^2, standard gravity
R_AIR = 8.31432e3 / 28.9644   # J/(kg K), R* / M0 (US76 eq. 1 constants)
GAMMA = 1.4
R_EARTH = 6356.766e3          # m, US76 effective earth radius for geopotential height
H_BASE = np.array([0.0, 11.0, 20.0, 32.0, 47.0, 51.0, 71.0, 84.852]) * 1e3   # US76 Table 4
LAPSE = np.array([-6.5, 0.0, 1.0, 2.8, 0.0, -2.8, -2.0]) * 1e-3              # K/m
T0, P0 = 288.15, 101325.0
KNOT = 1852.0 / 3600.0        # m/s per knot


def _bases():
    T = [T0]
    P = [P0]
    for i, L in enumerate(LAPSE[:-1]):
        dh = H_BASE[i + 1] - H_BASE[i]
        T1 = T[-1] + L * dh
        if L == 0:
            P1 = P[-1] * np.exp(-G0 * dh / (R_AIR * T[-1]))          # US76 eq. 33b
        else:
            P1 = P[-1] * (T[-1] / T1) ** (G0 / (R_AIR * L))          # US76 eq. 33a
        T.append(T1)
        P.append(P1)
    return np.array(T), np.array(P)


T_BASE, P_BASE = _bases()
RHO0 = P0 / (R_AIR * T0)  # 1.225 kg/m^3


def atmosphere(altitude_m) -> dict:
    """Temperature, pressure, density and speed of sound at geometric altitude(s).

    Parameters
    ----------
    altitude_m : array_like
        Geometric altitude above mean sea level, m (-5000 to 86000).

    Returns
    -------
    dict of ndarray
        ``temperature`` [K], ``pressure`` [Pa], ``density`` [kg/m^3], ``speed_of_sound`` [m/s].
    """
    z = np.asarray(altitude_m, dtype=float)
    if np.any(z < -5000) or np.any(z > 86000) or not np.all(np.isfinite(z)):
        raise InputError(f"atmosphere: altitude {z.tolist()} m outside the US76 range -5 km .. 86 km. "
                         "Fix: check the altitude units (metres).")
    h = R_EARTH * z / (R_EARTH + z)                                   # US76 eq. 18
    i = np.clip(np.searchsorted(H_BASE, h, side="right") - 1, 0, LAPSE.size - 1)
    L, Tb, Pb, hb = LAPSE[i], T_BASE[i], P_BASE[i], H_BASE[i]
    T = Tb + L * (h - hb)
    with np.errstate(divide="ignore", invalid="ignore"):
        P = np.where(L == 0, Pb * np.exp(-G0 * (h - hb) / (R_AIR * Tb)),
                     Pb * (Tb / T) ** (G0 / (R_AIR * np.where(L == 0, 1.0, L))))
    rho = P / (R_AIR * T)                                             # US76 eq. 42
    a = np.sqrt(GAMMA * R_AIR * T)                                    # US76 eq. 50
    return {"temperature": T, "pressure": P, "density": rho, "speed_of_sound": a}


def altitude_from_density(rho_si) -> np.ndarray:
    """Geometric altitude (m) whose US76 density is ``rho_si`` (kg/m^3)."""
    rho = np.atleast_1d(np.asarray(rho_si, dtype=float))
    lo, hi = float(atmosphere(86000.0)["density"]), float(atmosphere(-5000.0)["density"])
    if np.any(rho <= lo) or np.any(rho >= hi):
        raise InputError(f"atmosphere: density {rho.tolist()} kg/m^3 outside the US76 range "
                         f"({lo:.3g}, {hi:.3g}). Fix: check the density units.")
    out = np.array([brentq(lambda z, r=r: float(atmosphere(z)["density"]) - r, -5000.0, 86000.0,
                           xtol=1e-6) for r in rho])
    return out.reshape(np.shape(rho_si))


@dataclass(frozen=True)
class Units:
    """Model units relative to SI: metres per model length unit, kg/m^3 per model density unit.

    Use :meth:`named` for ``"si"``, ``"english_in"`` (in, lbf s^2/in) and ``"english_ft"``
    (ft, slug).
    """

    length: float = 1.0
    density: float = 1.0

    def __post_init__(self):
        if not (self.length > 0 and self.density > 0):
            raise InputError("Units: length and density factors must be > 0.")

    @classmethod
    def named(cls, name: str) -> "Units":
        """Preset unit systems (DESIGN.md section 3)."""
        table = {"si": cls(1.0, 1.0),
                 "english_in": cls(0.0254, 175.126835 / 0.0254 ** 3),
                 "english_ft": cls(0.3048, 14.5939029 / 0.3048 ** 3)}
        if name not in table:
            raise InputError(f"Units: unknown unit system {name!r}. Fix: use one of {sorted(table)}.")
        return table[name]


def flight_labels(velocity, density, units: Units = Units()) -> dict:
    """KTAS, KEAS, pressure altitude from density, speed of sound and Mach of model-unit points.

    Parameters
    ----------
    velocity, density : array_like
        True airspeed and density in model units.
    units : Units

    Returns
    -------
    dict of ndarray
        ``ktas``, ``keas`` (V sqrt(rho/rho0), knots), ``altitude_m`` (US76 density altitude),
        ``mach`` (V / a at that altitude).
    """
    V = np.asarray(velocity, dtype=float) * units.length
    rho = np.asarray(density, dtype=float) * units.density
    alt = altitude_from_density(rho)
    a = atmosphere(alt)["speed_of_sound"]
    return {"ktas": V / KNOT, "keas": V * np.sqrt(rho / RHO0) / KNOT, "altitude_m": alt,
            "mach": V / a}
