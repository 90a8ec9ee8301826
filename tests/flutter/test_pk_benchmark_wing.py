"""Fast p-k against the plain per-root p-k on the benchmark wing (benchmarks/flutter.py), reduced size.

The benchmark's 30-mode cantilever wing with Theodorsen strip GAFs, swept at 60 velocities (instead of
200) and two Mach numbers: every flutter crossing of the fast solver (Newton k-matching, one LU per
root per iteration, continuation) must agree with the plain per-root p-k (full eigen-decomposition per
root per iteration, crossing located by bisection; tests/flutter/flutter_plain_pk.py) to 0.1% in
velocity and frequency. The batched multi-case solve must reproduce the per-case solves.
"""
from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from flutter.pk import pk_solve, pk_solve_many
from flutter.system import ModalSystem, StructuralDamping

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "flutter.py"
MACHS = (0.2, 0.6)
RHO = 1.225


def _bench():
    spec = importlib.util.spec_from_file_location("benchmark_flutter_wing", BENCH)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def wing():
    bench = _bench()
    M, K, strips = bench.wing_model()
    gaf = bench.gafs(strips)
    system = ModalSystem(M, K, structural=StructuralDamping(g=0.0))
    V = np.linspace(20.0, 400.0, 60)
    many = pk_solve_many(system, gaf, [(V, RHO, m) for m in MACHS])
    return bench, M, K, gaf, system, V, many


def test_fast_crossings_match_plain_pk(wing):
    bench, M, K, gaf, _, _, many = wing
    n_flutter = 0
    for m, ds in zip(MACHS, many):
        assert bool(ds.converged.all())
        pairs = bench.plain_crossings(M, K, gaf, ds, RHO, m)
        assert len(pairs) >= 1  # the wing flutters at every Mach number (benchmark: two modes)
        for V_fast, V_plain, f_fast, f_plain in pairs:
            assert abs(V_fast / V_plain - 1) < 1e-3
            assert abs(f_fast / f_plain - 1) < 1e-3
        n_flutter += len(pairs)
    assert n_flutter >= 2 * len(MACHS)


def test_batched_cases_equal_single_solves(wing):
    _, _, _, gaf, system, V, many = wing
    for m, ds in zip(MACHS, many):
        one = pk_solve(system, gaf, V, density=RHO, mach=m)
        np.testing.assert_allclose(ds.eigenvalue.values, one.eigenvalue.values, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(ds.crossing_velocity.values, one.crossing_velocity.values, rtol=1e-9)
        assert list(ds.crossing_kind.values) == list(one.crossing_kind.values)
