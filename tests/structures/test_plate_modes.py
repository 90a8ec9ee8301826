"""Plate modal validation: CQUAD4/CTRIA3 decks solved end to end (read_model + compute_modes).

References (classical thin-plate theory, Leissa, "Vibration of Plates", NASA SP-160, 1969):

* simply supported rectangle (SP-160 section 4.2, eq. 4.21): omega_mn = pi^2 (m^2/a^2 + n^2/b^2)
  sqrt(D / (rho h)), D = E h^3 / (12 (1 - nu^2));
* cantilever square plate (C-F-F-F, SP-160 section 4.3, nu = 0.3, values of Barton 1951):
  lambda = omega a^2 sqrt(rho h / D) = 3.492, 8.525, 21.43, 27.33 for the first four modes.
  Barton's values come from a few-term Ritz (upper-bound) solution; converged values are a few
  tenths of a percent lower, which the 2 % tolerance covers.

The in-plane membrane constraints of the "simply supported" deck (T1, T2 fixed on the edges) do not
affect the bending modes of a flat plate: membrane and bending decouple.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from plate_decks import plate_deck
from structures.bdf import read_model
from structures.modal import compute_modes

E, NU, RHO, T = 7.0e10, 0.3, 2700.0, 0.005
D_FLEX = E * T ** 3 / (12 * (1 - NU ** 2))           # flexural rigidity (SP-160 eq. 1.3)


def ss_reference(a: float, b: float, count: int) -> np.ndarray:
    """Lowest ``count`` simply-supported frequencies [Hz] (SP-160 eq. 4.21)."""
    omegas = sorted(np.pi ** 2 * (m * m / a ** 2 + n * n / b ** 2) * np.sqrt(D_FLEX / (RHO * T))
                    for m in range(1, 8) for n in range(1, 8))
    return np.array(omegas[:count]) / (2 * np.pi)


CANTILEVER_LAMBDA = np.array([3.492, 8.525, 21.43, 27.33])   # SP-160 sec. 4.3 (Barton), nu = 0.3


def frequencies(path: Path, nmodes: int, mass: str) -> np.ndarray:
    ds = compute_modes(read_model(path), nmodes, mass=mass)
    return np.asarray(ds["frequency"].values, dtype=float)


@pytest.mark.parametrize("mass,nx,ny,tol", [("lumped", 20, 12, 0.01), ("consistent", 30, 18, 0.02)])
def test_simply_supported_rectangle(tmp_path, mass, nx, ny, tol):
    """Measured errors: lumped 20x12 -0.15/-0.48/-0.29/+0.60 %; consistent 30x18 +0.24/+0.36/+0.90/
    +1.34 % (consistent 20x12 would be +0.6..+3.1 %: consistent mass converges from above)."""
    deck = plate_deck(tmp_path / "ss.bdf", a=1.0, b=0.6, t=T, nx=nx, ny=ny, boundary="ss")
    f = frequencies(deck, 4, mass)
    np.testing.assert_allclose(f, ss_reference(1.0, 0.6, 4), rtol=tol)


def test_cantilever_square_plate(tmp_path):
    """Measured lambda (lumped, 20x20): 3.469, 8.487, 21.25, 27.03 (-0.65/-0.45/-0.84/-1.11 %)."""
    deck = plate_deck(tmp_path / "cfff.bdf", a=1.0, b=1.0, t=T, nx=20, ny=20, boundary="cantilever")
    f = frequencies(deck, 4, "lumped")
    lam = 2 * np.pi * f * 1.0 ** 2 * np.sqrt(RHO * T / D_FLEX)
    np.testing.assert_allclose(lam, CANTILEVER_LAMBDA, rtol=0.02)


ROT_Z90 = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])     # in-plane, about z
ROT_VERTICAL = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])  # plate in the y-z plane


@pytest.mark.parametrize("rotation", [ROT_Z90, ROT_VERTICAL], ids=["in-plane 90 deg", "vertical"])
def test_rotated_plate_same_frequencies(tmp_path, rotation):
    """The cantilever deck (all six components clamped, frame independent) rotated in space.

    Measured: largest relative difference 8e-11 (in-plane) and 1e-12 (vertical)."""
    kw = dict(a=1.0, b=0.6, t=T, nx=10, ny=6, boundary="cantilever", nmodes=8)
    base = frequencies(plate_deck(tmp_path / "base.bdf", **kw), 8, "consistent")
    turned = frequencies(plate_deck(tmp_path / "turned.bdf", rotation=rotation, **kw), 8,
                         "consistent")
    np.testing.assert_allclose(turned, base, rtol=1e-6)


@pytest.mark.parametrize("mass,tol", [("lumped", 0.01), ("consistent", 0.025)])
def test_tria_mesh_simply_supported(tmp_path, mass, tol):
    """CTRIA3 (DKT) mesh, each quad of a 20x12 grid split along G1-G3.

    Measured errors: lumped -0.18/-0.38/-0.53/-0.30 %; consistent +0.60/+1.01/+1.89/+2.20 %.
    """
    deck = plate_deck(tmp_path / "tria.bdf", a=1.0, b=0.6, t=T, nx=20, ny=12, boundary="ss",
                      element="CTRIA3")
    f = frequencies(deck, 4, mass)
    np.testing.assert_allclose(f, ss_reference(1.0, 0.6, 4), rtol=tol)


def test_blank_mid3_is_the_thin_plate_limit(tmp_path):
    """MID3 blank (no shear flexibility) and MID3 = MID1 differ by the transverse-shear effect only,
    ~(pi t / wavelength)^2 / (1 - nu) < 0.1 % for a/t = 200."""
    kw = dict(a=1.0, b=0.6, t=T, nx=20, ny=12, boundary="ss")
    shear = frequencies(plate_deck(tmp_path / "s.bdf", mid3=True, **kw), 4, "lumped")
    kirchhoff = frequencies(plate_deck(tmp_path / "k.bdf", mid3=False, **kw), 4, "lumped")
    assert np.all(kirchhoff >= shear * (1 - 1e-9))
    np.testing.assert_allclose(kirchhoff, shear, rtol=1e-3)
