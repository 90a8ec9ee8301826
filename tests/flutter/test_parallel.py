"""flutter.parallel / pk_solve_many(workers=...): the batched results to a stated tolerance (not
bit-identical: a batch of roots from several cases rounds differently from one case's roots), the
in-process single-case results to 1e-12, warnings of the workers issued in the caller, bad worker
counts refused. Run pinned to one core and with OPENBLAS_NUM_THREADS=1 and 2 as well."""
from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from aero.strip import section_gaf
from flutter.parallel import map_cases
from flutter.pk import pk_solve, pk_solve_many
from structures.common.errors import InputError
from test_pk_typical_section import A, B, RHO, gaf, section

NUMBERS = ("eigenvalue", "damping", "frequency", "k", "eigenvector", "crossing_velocity",
           "crossing_density", "crossing_frequency", "crossing_eigenvector")


def _assert_close(a: xr.Dataset, b: xr.Dataset, rel: float) -> None:
    """Same layout, flags and crossings; numbers within ``rel`` of each variable's largest |value|."""
    assert a.sizes == b.sizes and a.attrs == b.attrs
    for name in a.coords:
        np.testing.assert_array_equal(a[name].values, b[name].values)
    np.testing.assert_array_equal(a.converged.values, b.converged.values)
    np.testing.assert_array_equal(a.crossing_root.values, b.crossing_root.values)
    assert list(a.crossing_kind.values) == list(b.crossing_kind.values)
    np.testing.assert_array_equal(a.crossing_converged.values, b.crossing_converged.values)
    for name in NUMBERS:
        x, y = a[name].values, b[name].values
        if x.size:
            np.testing.assert_allclose(y, x, rtol=0, atol=rel * np.nanmax(np.abs(x)), err_msg=name)


def test_workers_give_the_batched_results():
    cases = [(np.linspace(0.2, 3.0, 40), RHO, 0.0), (np.linspace(0.3, 2.5, 30), RHO, 0.0),
             (np.linspace(0.5, 2.0, 20), RHO, 0.0)]
    batched = pk_solve_many(section(), gaf, cases, refc=2.0)
    forked = pk_solve_many(section(), gaf, cases, refc=2.0, workers=2)
    assert [ds.sizes["crossing"] for ds in batched] == [2, 1, 0]  # flutter 2.18, divergence 2.83
    for case, a, b in zip(cases, batched, forked):
        _assert_close(a, b, 1e-11)       # measured 2e-14 (eigenvalues) .. 2e-13 (eigenvectors)
        alone = pk_solve(section(), gaf, case[0], density=case[1], mach=case[2], refc=2.0)
        _assert_close(alone, b, 1e-12)   # the same kernels on the same batch: measured 0


def test_worker_warnings_reach_the_caller():
    k = np.linspace(0.01, 0.2, 8)
    ds = xr.Dataset({"Q": (("mach", "k", "mode_i", "mode_j"), section_gaf(k, A, B)[None])},
                    coords={"mach": [0.0], "k": k, "mode_i": [1, 2], "mode_j": [1, 2]},
                    attrs={"refc": 2.0, "rhoref": 1.0})
    cases = [([1.0, 2.0, 3.0], RHO, 0.0), ([8.0, 9.0], RHO, 0.0)]
    with pytest.warns(RuntimeWarning, match=r"root 2 needs k=[0-9.]+ at V=1 .*outside the tabulated"):
        out = pk_solve_many(section(), ds, cases, workers=2)
    assert not bool(out[0].converged.sel(root=2, velocity=1.0))
    assert bool(out[1].converged.all())


def test_bad_worker_counts():
    with pytest.raises(InputError, match="workers"):
        pk_solve_many(section(), gaf, [(1.0, RHO, 0.0)], refc=2.0, workers=0)
    with pytest.raises(ValueError, match="workers"):
        map_cases(abs, [1, 2], 0)
    assert map_cases(abs, [-1, 2, -3], 2) == [1, 2, 3]
