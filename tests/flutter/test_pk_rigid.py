"""p-k with a rigid-body mode on which the aerodynamics act not at all (surge of a free aircraft).

Such a mode is an exact, defective double root p = 0 of the flutter equation (M p^2 u = 0: its
eigenvector appears twice, and T'(0) u = 0). Reference: the same system without it. Nastran's
bah_plane QHH (plunge and pitch free) is extended by a decoupled unit-mass mode with zero
stiffness and zero GAFs; the roots of the other modes must not change, and the added root must be
p = 0 (no NaN, no copy of another rigid root).
"""
from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from flutter.pk import pk_solve
from flutter.system import ModalSystem
from flutter_nastran import DATA, bah_qhh_dataset, f06_modes_used


def test_decoupled_rigid_mode_is_an_exact_zero_root():
    gaf = bah_qhh_dataset()
    gm, gk, _ = f06_modes_used(DATA / "bah_plane" / "bah_plane.f06")
    n = gm.size
    Q = gaf["Q"].transpose("mach", "k", "mode_i", "mode_j").values
    Q3 = np.zeros(Q.shape[:2] + (n + 1, n + 1), dtype=complex)
    Q3[..., 1:, 1:] = Q                       # mode 0: surge, no aerodynamic force at all
    ext = xr.Dataset({"Q": (("mach", "k", "mode_i", "mode_j"), Q3)},
                     coords={"mach": gaf["mach"].values, "k": gaf["k"].values,
                             "mode_i": np.arange(n + 1), "mode_j": np.arange(n + 1)},
                     attrs=gaf.attrs)
    V = np.linspace(30.0, 300.0, 10)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)   # roots 9-10 above the k table
        base = pk_solve(ModalSystem(np.diag(gm), np.diag(gk)), gaf, V, density=1.225, mach=0.2)
        more = pk_solve(ModalSystem(np.diag(np.r_[1.0, gm]), np.diag(np.r_[0.0, gk])), ext, V,
                        density=1.225, mach=0.2)
    p = more["eigenvalue"].values
    assert np.all(np.isfinite(p))
    np.testing.assert_array_equal(np.abs(p[:, 0]), 0.0)        # the surge root: exactly zero
    np.testing.assert_allclose(p[:, 1:], base["eigenvalue"].values, rtol=1e-7, atol=1e-9)
