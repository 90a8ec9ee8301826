"""Roger RFA + python-control state-space flutter as a cross-check of p-k (typical section)."""
from __future__ import annotations

import control
import numpy as np
import pytest
import xarray as xr

from aero.rfa import fit_roger
from aero.strip import section_gaf
from flutter.pk import pk_solve
from flutter.statespace import aeroelastic_statespace, statespace_solve
from flutter.tracking import assign
from structures.common.errors import InputError
from test_pk_typical_section import A, B, section

K = np.concatenate([[0.0, 0.01, 0.02, 0.05], np.linspace(0.1, 2.0, 20)])


def theodorsen_gaf():
    return xr.Dataset({"Q": (("mach", "k", "mode_i", "mode_j"), section_gaf(K, A, B)[None])},
                      coords={"mach": [0.0], "k": K, "mode_i": [1, 2], "mode_j": [1, 2]},
                      attrs={"refc": 2 * B, "rhoref": 1.0})


def test_roger_fit_recovers_exact_form():
    """A Q that is exactly of Roger's form is fitted exactly (least squares is consistent)."""
    rng = np.random.default_rng(1)
    beta = np.array([0.1, 0.5])
    Atrue = rng.normal(size=(5, 3, 3))
    p = 1j * K[:, None]
    E = np.concatenate([np.ones_like(p), p, p * p, p / (p + beta)], axis=1)
    Q = np.einsum("kt,tij->kij", E, Atrue)
    ds = xr.Dataset({"Q": (("mach", "k", "mode_i", "mode_j"), Q[None])},
                    coords={"mach": [0.3], "k": K, "mode_i": [1, 2, 3], "mode_j": [1, 2, 3]},
                    attrs={"refc": 1.0})
    rfa = fit_roger(ds, 0.3, beta=beta)
    np.testing.assert_allclose(rfa.A, Atrue, atol=1e-9)
    assert rfa.fit_error < 1e-12
    with pytest.raises(InputError, match="not tabulated"):
        fit_roger(ds, 0.5)


def test_statespace_flutter_matches_pk():
    """RFA fit of Theodorsen (4 lags, 0.3% error): flutter within 1% of p-k in speed and frequency."""
    rfa = fit_roger(theodorsen_gaf(), 0.0)
    assert rfa.fit_error < 0.01
    sys_ = section()
    ss = aeroelastic_statespace(sys_.mass, sys_.damping, sys_.stiffness, rfa, 1.0, 1.0)
    assert isinstance(ss, control.StateSpace) and ss.nstates == 2 * (2 + rfa.beta.size)
    sd = statespace_solve(sys_, rfa, np.linspace(0.05, 3.0, 300), density=1.0)
    pk = pk_solve(sys_, lambda m, k: section_gaf(k, A, B), np.linspace(0.05, 3.0, 60), density=1.0,
                  mach=0.0, refc=2 * B)
    fl = int(np.flatnonzero(pk.crossing_kind.values == "flutter")[0])
    assert sd.sizes["crossing"] == 1
    assert abs(float(sd.crossing_velocity[0]) / float(pk.crossing_velocity[fl]) - 1) < 0.01
    assert abs(float(sd.crossing_frequency[0]) / float(pk.crossing_frequency[fl]) - 1) < 0.01


def test_assign_follows_vectors_not_order():
    """Two roots whose frequencies cross: correlation keeps each root on its own eigenvector,
    where sorting by frequency (or nearest eigenvalue alone) would swap them."""
    u = np.eye(2, dtype=complex)
    p_old = np.array([1.0j, 1.1j])
    p_new = np.array([1.12j, 1.08j])              # mode 1 now above mode 2
    U_new = np.eye(2, dtype=complex)
    assert assign(p_old, u, p_new, U_new).tolist() == [0, 1]
