"""Test-session settings: one BLAS / OpenMP thread per process.

The suite's matrices are small: on two cores, BLAS threads cost more in start-up than they save
(the README's test command took 642 s unpinned and 558 s pinned to one core at c02447d), and
results that depend on the thread count (the example's FFFW sway pair, 2.5e-5 apart, mixes by
2.5e-6 with it) are the same on every machine. The variables reach the CLI subprocesses too;
a library already loaded is limited at run time.

Tests run one process per core instead (pytest-xdist, ``-n auto`` in pyproject.toml): as many
workers as cores this process may run on, so ``taskset -c 0 pytest`` runs in one process, as
without xdist. (xdist's own count asks psutil when it is installed, which counts the machine's
physical cores whatever the affinity.)
"""
from __future__ import annotations

import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

from threadpoolctl import threadpool_limits  # noqa: E402  (after the variables, by design)

threadpool_limits(limits=1)


def pytest_xdist_auto_num_workers(config) -> int:
    """Workers for ``-n auto``: the cores this process may run on; 0 (no workers, the tests run
    in this process) on one core."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return cores if cores and cores > 1 else 0
