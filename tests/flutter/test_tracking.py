"""p-k root tracking through a frequency crossing (continuity + eigenvector correlation, no sorting)."""
from __future__ import annotations

import numpy as np

from flutter.pk import pk_solve
from flutter.system import ModalSystem


def crossing_gaf(eps):
    """Aerodynamic stiffness raising mode 1 and lowering mode 2, aerodynamic damping on both,
    and a weak coupling ``eps``: omega_1^2 = 1 + q/2, omega_2^2 = 1.44 - q/2 cross at q = 0.44."""
    def gaf(mach, k):
        k = np.asarray(k, dtype=float)
        Q = np.zeros((k.size, 2, 2), dtype=complex)
        Q[:, 0, 0] = -0.5 - 0.05j * k
        Q[:, 1, 1] = 0.5 - 0.08j * k
        Q[:, 0, 1] = Q[:, 1, 0] = eps
        return Q
    return gaf


def test_roots_keep_their_modes_through_a_crossing():
    V = np.linspace(0.05, 1.3, 40)          # q = V^2/2 passes 0.44 at V = 0.94
    ds = pk_solve(ModalSystem(np.eye(2), np.diag([1.0, 1.44])), crossing_gaf(0.0), V,
                  density=1.0, mach=0.0, refc=2.0)
    f1, f2 = ds.frequency.sel(root=1).values, ds.frequency.sel(root=2).values
    assert f1[0] < f2[0] and f1[-1] > f2[-1]          # the frequencies did cross
    assert np.all(np.diff(f1) > 0) and np.all(np.diff(f2) < 0)
    u = np.abs(ds.eigenvector.values)
    np.testing.assert_allclose(u[:, 0, 0], 1.0)       # root 1 stays mode 1 ...
    np.testing.assert_allclose(u[:, 1, 1], 1.0)       # ... and root 2 stays mode 2
    assert ds.converged.all()


def test_weakly_coupled_crossing_stays_continuous():
    """With a small coupling the crossing becomes a veering: each root's frequency stays smooth."""
    V = np.linspace(0.05, 1.3, 40)
    ds = pk_solve(ModalSystem(np.eye(2), np.diag([1.0, 1.44])), crossing_gaf(0.01), V,
                  density=1.0, mach=0.0, refc=2.0)
    for r in (1, 2):
        f = ds.frequency.sel(root=r).values
        assert np.abs(np.diff(f)).max() < 0.05          # no jump between neighbouring points
    assert ds.converged.all()
