"""Benchmark: p-k with tracking, 30 modes x 200 velocities x 3 Mach numbers.

Synthetic but realistic aeroelastic model: a uniform cantilever wing (semi-span 8 m, chord 1.5 m,
elastic axis at 35% chord, CG 10% chord behind it) with 15 bending and 15 torsion modes coupled
through the static imbalance, and Theodorsen strip GAFs (40 strips, Prandtl-Glauert lift slope per
Mach) tabulated at 24 reduced frequencies. Prints total seconds, wall and CPU (the machine is shared,
so wall time is noisy; the load average and the time of a fixed reference workload just before and
after are printed beside them), of one ``pk_solve`` per Mach number, of the three in one ``pk_solve_many`` batch and on two worker processes (``workers=2``, the
machine's two cores), seconds per (velocity x root), peak memory, and the
agreement of every crossing with a plain per-root p-k (full eigen-decomposition per root per
iteration, located by bisection).

Run: ``PYTHONPATH=. python benchmarks/flutter.py``
"""
from __future__ import annotations

import json
import os
import sys
import time
import tracemalloc
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "flutter"))

from aero.strip import strip_gaf  # noqa: E402
from flutter.pk import pk_solve, pk_solve_many  # noqa: E402
from flutter.results import is_flutter  # noqa: E402
from flutter.system import ModalSystem, StructuralDamping  # noqa: E402

L, CHORD, NSTRIP = 8.0, 1.5, 40
A_EA, X_THETA, R2 = -0.3, 0.2, 0.25   # semichords
MASS = 30.0                            # kg/m
F_BEND, F_TORS = 3.0, 12.0             # first bending / torsion, Hz
N_BEND = N_TORS = 15
MACHS = (0.2, 0.4, 0.6)
K_GRID = np.concatenate([[1e-3, 0.01, 0.03, 0.05, 0.08], np.linspace(0.1, 1.0, 10),
                         [1.3, 1.7, 2.2, 3.0, 4.0, 6.0, 9.0, 14.0, 20.0, 40.0, 80.0, 160.0, 250.0, 500.0]])


def beam_shapes(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cantilever bending eigenfunctions (Blevins Table 8-1) at y, shape (N_BEND, ny), and beta L."""
    bl = np.array([1.8751041, 4.6940911, 7.8547574, 10.9955407]
                  + [(2 * j - 1) * np.pi / 2 for j in range(5, N_BEND + 1)])
    out = np.empty((N_BEND, y.size))
    for j, b in enumerate(bl):
        x = b * y / L
        if j < 4:
            s = (np.cosh(b) + np.cos(b)) / (np.sinh(b) + np.sin(b))
            out[j] = np.cosh(x) - np.cos(x) - s * (np.sinh(x) - np.sin(x))
        else:  # asymptotic form, free of cosh/sinh cancellation
            out[j] = np.sin(x) - np.cos(x) + np.exp(-x) + (-1) ** (j + 1) * np.exp(-(b - x))
    return out, bl


def wing_model():
    """Modal M, K and strip geometry of the benchmark wing."""
    b = CHORD / 2
    dy = L / NSTRIP
    y = (np.arange(NSTRIP) + 0.5) * dy
    hb, bl = beam_shapes(y)
    at = np.array([np.sqrt(2) * np.sin((2 * j - 1) * np.pi * y / (2 * L)) for j in range(1, N_TORS + 1)])
    nm = N_BEND + N_TORS
    plunge = np.zeros((nm, NSTRIP))
    pitch = np.zeros((nm, NSTRIP))
    plunge[:N_BEND] = hb
    pitch[N_BEND:] = at
    S = MASS * X_THETA * b
    Ia = MASS * R2 * b * b
    M = dy * (MASS * plunge @ plunge.T + S * (plunge @ pitch.T + pitch @ plunge.T) + Ia * pitch @ pitch.T)
    w_b = 2 * np.pi * F_BEND * (bl / bl[0]) ** 2
    w_t = 2 * np.pi * F_TORS * np.arange(1, 2 * N_TORS, 2)
    gen_b = dy * MASS * np.sum(hb * hb, axis=1)
    gen_t = dy * Ia * np.sum(at * at, axis=1)
    K = np.diag(np.concatenate([w_b ** 2 * gen_b, w_t ** 2 * gen_t]))
    return M, K, dict(y=y, width=np.full(NSTRIP, dy), semichord=np.full(NSTRIP, b),
                      a=np.full(NSTRIP, A_EA), plunge=plunge, pitch=pitch)


def gafs(strips: dict) -> xr.Dataset:
    """Theodorsen strip GAFs at each Mach with a Prandtl-Glauert lift slope."""
    sets = [strip_gaf(K_GRID, refc=CHORD, mach=m, rhoref=1.225,
                      lift_slope=2 * np.pi / np.sqrt(1 - m * m), **strips) for m in MACHS]
    return xr.concat(sets, dim="mach")


def plain_crossings(M, K, gaf, ds, rho, mach):
    """Every crossing of the fast sweep re-located by the plain per-root p-k (bisection)."""
    import flutter_plain_pk as plain

    g1 = gaf.sel(mach=mach)
    q_of_k = plain.make_q(g1.k.values, g1.Q.values)
    out = []
    for c in range(ds.sizes["crossing"]):
        if not is_flutter(ds.crossing_kind.values[c]):
            continue
        r = int(ds.crossing_root[c]) - 1
        V = ds.velocity.values
        i = int(np.searchsorted(V, float(ds.crossing_velocity[c]))) - 1
        p_i = plain.root_at(M, K, np.zeros_like(M), q_of_k, CHORD / 2, V[i], rho,
                            complex(ds.eigenvalue.values[i, r]))[0]
        Vc, fc = plain.crossing(M, K, np.zeros_like(M), q_of_k, CHORD / 2, V[i], V[i + 1], rho, p_i)
        out.append((float(ds.crossing_velocity[c]), Vc, float(ds.crossing_frequency[c]), fc))
    return out


def reference_seconds() -> float:
    """Seconds of a fixed workload shaped like the solver's (200 LUs of 30 x 30 complex matrices
    and 20,000 small numpy calls) on one BLAS thread: the machine's speed at the moment, to read
    the timings against (the cores are shared, so it varies by up to 2x from minute to minute)."""
    from scipy.linalg.lapack import zgetrf
    from threadpoolctl import threadpool_limits

    rng = np.random.default_rng(0)
    T = rng.standard_normal((200, 30, 30)) + 1j * rng.standard_normal((200, 30, 30))
    x = rng.standard_normal(30)
    with threadpool_limits(limits=1, user_api="blas"):
        t0 = time.perf_counter()
        for t in T:
            zgetrf(t)
        for _ in range(20000):
            np.abs(x)
        return time.perf_counter() - t0


def main():
    M, K, strips = wing_model()
    gaf = gafs(strips)
    system = ModalSystem(M, K, structural=StructuralDamping(g=0.0))
    velocities = np.linspace(20.0, 400.0, 200)
    rho = 1.225
    pk_solve(system, gaf.isel(mach=[0]), velocities[:3], density=rho, mach=MACHS[0])  # warm-up
    ref_before = min(reference_seconds() for _ in range(3))
    load_before = os.getloadavg()
    t0, c0 = time.perf_counter(), time.process_time()
    results = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for m in MACHS:
            results.append(pk_solve(system, gaf, velocities, density=rho, mach=m))
    total, cpu = time.perf_counter() - t0, time.process_time() - c0
    load_after = os.getloadavg()
    ref_after = min(reference_seconds() for _ in range(3))
    t0, c0 = time.perf_counter(), time.process_time()  # the same three sweeps in one batch
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        batched = pk_solve_many(system, gaf, [(velocities, rho, m) for m in MACHS])
    total_b, cpu_b = time.perf_counter() - t0, time.process_time() - c0
    same = all(np.allclose(a.crossing_velocity.values, b.crossing_velocity.values, rtol=1e-9)
               for a, b in zip(results, batched))
    t0 = time.perf_counter()  # the three sweeps on two worker processes (flutter.parallel)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        forked = pk_solve_many(system, gaf, [(velocities, rho, m) for m in MACHS], workers=2)
    total_w = time.perf_counter() - t0
    same_w = all(np.array_equal(a.eigenvalue.values, b.eigenvalue.values)
                 for a, b in zip(results, forked))
    tracemalloc.start()  # separate, untimed pass: tracemalloc slows numpy allocation
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pk_solve(system, gaf, velocities, density=rho, mach=MACHS[0])
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    n_root = system.n
    agreement = []
    for m, ds in zip(MACHS, results):
        for Vf, Vp, ff, fp in plain_crossings(M, K, gaf, ds, rho, m):
            agreement.append({"mach": m, "V_fast": Vf, "V_plain": Vp, "dV_rel": Vf / Vp - 1,
                              "f_fast": ff, "f_plain": fp, "df_rel": ff / fp - 1})
    figures = {
        "modes": n_root, "velocities": velocities.size, "machs": len(MACHS),
        "total_seconds_wall": round(total, 3),
        "total_seconds_cpu": round(cpu, 3),
        "seconds_per_velocity_root_wall": total / (velocities.size * n_root * len(MACHS)),
        "seconds_per_velocity_root_cpu": cpu / (velocities.size * n_root * len(MACHS)),
        "load_average_1_5_15_before": [round(x, 2) for x in load_before],
        "load_average_1_5_15_after": [round(x, 2) for x in load_after],
        "reference_workload_seconds_before_after": [round(ref_before, 4), round(ref_after, 4)],
        "batched_pk_solve_many_seconds_wall": round(total_b, 3),
        "batched_pk_solve_many_seconds_cpu": round(cpu_b, 3),
        "batched_crossings_equal_per_mach": bool(same),
        "two_workers_seconds_wall": round(total_w, 3),
        "two_workers_results_identical": bool(same_w),
        "peak_traced_memory_MB_one_mach": round(peak / 2 ** 20, 2),
        "not_converged_points": int(sum((~ds.converged).sum() for ds in results)),
        "warnings": len(caught),
        "crossings": [{"mach": float(ds.crossing_mach[c]), "root": int(ds.crossing_root[c]),
                       "kind": str(ds.crossing_kind.values[c]),
                       "velocity": float(ds.crossing_velocity[c]),
                       "frequency": float(ds.crossing_frequency[c])}
                      for ds in results for c in range(ds.sizes["crossing"])],
        "max_rel_diff_vs_plain_pk": {
            "velocity": max((abs(a["dV_rel"]) for a in agreement), default=None),
            "frequency": max((abs(a["df_rel"]) for a in agreement), default=None)},
    }
    print(json.dumps(figures, indent=2))


if __name__ == "__main__":
    main()
