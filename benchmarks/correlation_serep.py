"""Benchmark: correlate() on an X-56A-sized problem (paper sec. III): 8262 grids x 6 = 49,572
A-set DOFs, 30 analysis modes (SEREP basis), 14 test modes measured at 120 DOFs.

Prints wall time and peak Python memory (tracemalloc) as ``key=value`` lines. The shapes are random
(only sizes matter here); run with ``PYTHONPATH=. python benchmarks/correlation_serep.py``.
"""
from __future__ import annotations

import time
import tracemalloc

import numpy as np
import xarray as xr

from structures.correlation import correlate
from structures.gvt import make_gvt_dataset


def main(n_grid: int = 8262, n_modes: int = 30, n_test: int = 14, n_measured: int = 120, repeat: int = 3) -> None:
    rng = np.random.default_rng(0)
    grids = np.arange(1, n_grid + 1)
    modes = xr.Dataset({"frequency": ("mode", np.sort(rng.uniform(1.0, 40.0, n_modes))),
                        "shape": (("mode", "dof"), rng.standard_normal((n_modes, 6 * n_grid))),
                        "generalized_mass": ("mode", np.ones(n_modes))},
                       coords={"mode": np.arange(1, n_modes + 1), "grid": ("dof", np.repeat(grids, 6)),
                               "component": ("dof", np.tile(np.arange(1, 7), n_grid))})
    dofs = np.sort(rng.choice(np.nonzero(modes["component"].values <= 3)[0], n_measured, replace=False))
    sub = modes.isel(dof=dofs, mode=slice(6, 6 + n_test))
    gvt = make_gvt_dataset(sub["frequency"].values * 1.02, sub["shape"].values
                           + 0.05 * rng.standard_normal((n_test, n_measured)),
                           sub["grid"].values, sub["component"].values, mode=np.arange(7, 7 + n_test))
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        correlate(modes, gvt)
        times.append(time.perf_counter() - t0)
    tracemalloc.start()
    correlate(modes, gvt)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    print(f"aset_dofs={6 * n_grid} serep_modes={n_modes} test_modes={n_test} measured_dofs={n_measured}")
    print(f"correlate_seconds_best={min(times):.4f} correlate_seconds_median={np.median(times):.4f}")
    print(f"correlate_peak_python_MB={peak / 1e6:.1f} modes_shape_MB={modes['shape'].nbytes / 1e6:.1f}")


if __name__ == "__main__":
    main()
