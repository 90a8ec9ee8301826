"""Process-wide settings for a program that runs the solver: never applied on import.

:func:`settle_process` is called by a program (the ``pipeline`` command, the worker of
``benchmarks/modal.py``) once its modules are imported, and again before it exits. Measured on the
61,206-DOF plate of ``benchmarks/modal.py`` (40 modes): whole run 2.59 -> 2.38 s (5 alternating
pairs, median) for the allocator, and an interpreter exit of 0.04 s instead of 0.33 s for the
collector.

- The cyclic garbage collector stops scanning the objects that exist (``gc.freeze``: the ~500k
  objects of numpy, scipy, xarray and pyNastran): its collections while pyNastran builds a deck's
  cards, and the interpreter's final ones, no longer walk them.
- glibc's allocator keeps freed memory for reuse (``mallopt``: blocks up to 32 MB from the heap,
  the heap trimmed only above 1 GB free, grown 64 MB at a time): element blocks and sparse
  temporaries of tens of MB are then not mapped, zero-filled by the kernel and unmapped again on
  every use (first assembly 0.84 -> 0.43 s). Peak memory grows by ~25 MB (416 -> 441 MB).
  Elsewhere (macOS, Windows, other C libraries) the allocator is left as it is.
- numpy stops asking the kernel for transparent huge pages for its arrays (``madvise``): with
  the kernel's THP defragmentation in its ``madvise`` mode, each such first touch may wait for
  memory compaction. Measured on the same run (8 alternating pairs, shared 2-core machine):
  system time 0.51 -> 0.36 s, wall 3.08 -> 2.89 s median, user time unchanged.
"""
from __future__ import annotations

import ctypes
import gc
import sys

try:                                                   # numpy >= 2 (1.26 has the alias too)
    from numpy._core.multiarray import _set_madvise_hugepage
except ImportError:
    from numpy.core.multiarray import _set_madvise_hugepage

#: glibc mallopt parameters (malloc.h) and the values set.
M_TRIM_THRESHOLD, M_TOP_PAD, M_MMAP_THRESHOLD = -1, -2, -3
ALLOCATOR = ((M_MMAP_THRESHOLD, 32 << 20), (M_TRIM_THRESHOLD, 1 << 30), (M_TOP_PAD, 64 << 20))


def settle_process() -> bool:
    """Freeze the objects that exist out of the garbage collector's scans, tune glibc malloc and
    turn off numpy's transparent-huge-page requests.

    Returns
    -------
    bool
        True when the allocator was tuned (Linux with glibc), else False.
    """
    gc.freeze()
    _set_madvise_hugepage(False)
    if not sys.platform.startswith("linux"):
        return False
    try:
        mallopt = ctypes.CDLL("libc.so.6").mallopt
    except (OSError, AttributeError):
        return False
    return all(mallopt(ctypes.c_int(param), ctypes.c_int(value)) == 1 for param, value in ALLOCATOR)
