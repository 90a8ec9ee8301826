"""Independent flight-point sweeps on worker processes, with their warnings issued in the caller.

The p-k sweeps of different Mach numbers or densities share nothing once the GAFs are built, so on
a machine with more than one core they run side by side. The workers are forked (POSIX): they
inherit the job (model, GAFs, cases) from the parent's memory, so nothing but the case index goes
to them and only the result comes back; a callable GAF that cannot be pickled works too. Where
``fork`` is not available (Windows) the cases run one after the other in the calling process.
Warnings raised in a worker are recorded there and issued again, in case order, by the caller.
What holds for the results: a worker runs exactly the code the calling process would run on that
case alone (same kernels, BLAS limited to one thread by the caller of the map, e.g.
:func:`flutter.pk.pk_solve_many`), so a forked result equals the in-process one; the tests check
this to 1e-12 relative rather than claim bit-identity, which memory alignment or a different BLAS
build may break. A result computed in a different batch (the lockstep batch of
:func:`flutter.pk.pk_solve_many` with ``workers=1``) differs in the last bits: see there.
The job is handed over in a module global, so one map runs at a time per process (not from two
threads at once).
"""
from __future__ import annotations

import multiprocessing
import warnings
from concurrent.futures import ProcessPoolExecutor
from typing import Callable, Sequence

_JOB: tuple | None = None   # (func, cases) of the running map, read by the forked workers


def _run(index: int):
    func, cases = _JOB
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = func(cases[index])
    return result, [(str(w.message), w.category) for w in caught]


def map_cases(func: Callable, cases: Sequence, workers: int) -> list:
    """``[func(case) for case in cases]``, on up to ``workers`` forked processes.

    Parameters
    ----------
    func : callable, case -> result (its result must pickle)
    cases : sequence of cases
    workers : int, processes at most (1: in the calling process)

    Returns
    -------
    list of results, in the order of ``cases``
    """
    global _JOB
    if workers < 1:
        raise ValueError(f"workers = {workers}; it must be >= 1")
    if workers == 1 or len(cases) < 2 or "fork" not in multiprocessing.get_all_start_methods():
        return [func(case) for case in cases]
    _JOB = (func, list(cases))
    try:
        context = multiprocessing.get_context("fork")
        with ProcessPoolExecutor(min(workers, len(cases)), mp_context=context) as pool:
            done = list(pool.map(_run, range(len(cases))))
    finally:
        _JOB = None
    results = []
    for result, caught in done:
        for message, category in caught:
            warnings.warn(message, category, stacklevel=2)
        results.append(result)
    return results
