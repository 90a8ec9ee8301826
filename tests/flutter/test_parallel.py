"""flutter.parallel / pk_solve_many(workers=...): the same results as the batched solve, warnings of
the workers issued in the caller, bad worker counts refused."""
from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from aero.strip import section_gaf
from flutter.parallel import map_cases
from flutter.pk import pk_solve_many
from structures.errors import InputError
from test_pk_typical_section import A, B, RHO, gaf, section


def test_workers_give_the_batched_results():
    cases = [(np.linspace(0.2, 3.0, 40), RHO, 0.0), (np.linspace(0.3, 2.5, 30), RHO, 0.0),
             (np.linspace(0.5, 2.0, 20), RHO, 0.0)]
    batched = pk_solve_many(section(), gaf, cases, refc=2.0)
    forked = pk_solve_many(section(), gaf, cases, refc=2.0, workers=2)
    for a, b in zip(batched, forked):
        xr.testing.assert_identical(a, b)


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
