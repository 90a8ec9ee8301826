"""Sparse factorisation of a symmetric positive definite matrix, behind one interface.

:func:`factorize` returns an object with ``solve(b)`` and a ``backend`` name. The backend is the
first importable one of:

- ``"pardiso"``: Intel MKL PARDISO through ``pypardiso`` (a dependency on x86-64 Linux and
  Windows, where the ``mkl`` wheels exist): a supernodal, threaded Cholesky factorisation
  (matrix type 2, real symmetric positive definite) with METIS nested-dissection ordering, given
  the upper triangle only.
- ``"superlu"``: scipy's SuperLU (always installed), used as a Cholesky-like LU: no pivoting,
  symmetric mode, ordered by minimum degree on the graph of DOF groups (grids).

CHOLMOD (``scikit-sparse``) is not a backend: it builds only against SuiteSparse headers from the
system, which the one-line install cannot provide.

``backend=`` or the environment variable ``FTP_SPARSE_BACKEND`` forces a backend (tests compare
them); an unknown or unavailable name raises :class:`InputError` listing the valid ones.

A singular matrix (in a modal solve: a massless mechanism, a motion with neither stiffness nor
mass) raises the same :class:`SolverError` on every backend: a zero or negative diagonal entry,
a failed factorisation, or a pivot below ``PIVOT_RATIO`` times its diagonal entry.
"""
from __future__ import annotations

import ctypes
import glob
import os
import sys
import weakref

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from structures.common.errors import InputError, SolverError, card_message

BACKENDS = ("pardiso", "superlu")
ENV_VAR = "FTP_SPARSE_BACKEND"
PIVOT_RATIO = 1e-11
PARDISO_SPD = 2                                # PARDISO mtype: real symmetric positive definite
PARDISO_ZERO_PIVOT = -4                        # PARDISO error: zero pivot (not positive definite)


class MasslessMechanism(SolverError):
    """K - sigma M failed the singularity test (:func:`massless_mechanism`)."""


def massless_mechanism(filename: str) -> MasslessMechanism:
    """The error for a singular shifted stiffness K - sigma M (a massless mechanism)."""
    return MasslessMechanism(card_message(
        "the shifted stiffness K - sigma M is singular: some motion has neither stiffness nor "
        "mass (a massless mechanism, e.g. a free rotation of grids without rotary inertia).",
        filename=filename,
        fix="constrain it (SPC), connect the free grids, or give that motion mass (CONM2 inertia, "
            "CBEAM instead of CBAR)."))


def available_backends() -> tuple[str, ...]:
    """Names of the backends importable here, in order of preference."""
    return tuple(name for name in BACKENDS if name == "superlu" or _pardiso_module() is not None)


def factorize(a: sp.spmatrix, *, groups: np.ndarray | None = None, filename: str = "",
              backend: str | None = None):
    """Factorise a sparse symmetric positive definite matrix.

    Parameters
    ----------
    a : sparse (n, n), symmetric positive definite (both triangles stored).
    groups : (n,) int, optional, the group (grid) of each row; orders the SuperLU factorisation
        (PARDISO orders by its own nested dissection).
    filename : str, the deck named in errors.
    backend : {'pardiso', 'superlu'}, optional; default ``$FTP_SPARSE_BACKEND``, else the first
        available one.

    Returns
    -------
    PardisoFactor or SuperLUFactor, with ``solve(b)`` for b of shape (n,) or (n, k) and
    ``backend``.

    Raises
    ------
    SolverError
        ``a`` is singular or not positive definite (a massless mechanism).
    InputError
        ``backend`` is unknown or not installed.
    """
    name = choose_backend(backend)
    a = sp.csr_matrix(a, dtype=float)
    diag = a.diagonal()
    if not np.all(np.isfinite(diag)) or np.any(diag <= 0.0):
        raise massless_mechanism(filename)
    if name == "pardiso":
        return PardisoFactor(a, filename)
    return SuperLUFactor(a.tocsc(), groups, filename)


def choose_backend(backend: str | None = None) -> str:
    """The backend :func:`factorize` uses: ``backend``, else ``$FTP_SPARSE_BACKEND``, else the
    first available one; InputError for an unknown or missing one."""
    name = backend or os.environ.get(ENV_VAR, "").strip().lower()
    available = available_backends()
    if not name:
        return available[0]
    if name not in BACKENDS:
        source = "backend=" if backend else ENV_VAR
        raise InputError(card_message(
            f"unknown sparse factorisation backend {name!r} (from {source}).",
            fix=f"use one of {', '.join(BACKENDS)}."))
    if name not in available:
        raise InputError(card_message(
            f"the sparse factorisation backend {name!r} is not installed.",
            fix=f"install it (pip install pypardiso; x86-64 Linux or Windows) or use one of "
                f"{', '.join(available)}."))
    return name


def free_cores() -> int:
    """Cores for a threaded factorisation: those this process may run on, less those other
    programs keep busy.

    The busy ones are the 1-minute load average, rounded, less one: a program that runs the
    solver repeatedly (a benchmark, a sweep) is itself about one unit of that load. On a shared
    machine an OpenMP thread that the scheduler takes away stalls every parallel region of the
    others; measured on 2 cores with a load average of ~4 (other programs), the whole
    61,206-DOF modal run took 4.50 s with one PARDISO thread against 4.91 s with two (median of
    6 alternating pairs).

    Returns
    -------
    int, at least 1.
    """
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:                       # not Linux
        cores = os.cpu_count() or 1
    try:
        busy = max(0, round(os.getloadavg()[0]) - 1)
    except (AttributeError, OSError):            # no load average (Windows)
        busy = 0
    return max(1, cores - busy)


def _pardiso_module():
    """The ``pypardiso`` module, or None when it (or MKL) is missing.

    pypardiso looks for ``libmkl_rt`` by a recursive search of the environment (~0.1 s per
    solver); pointing its documented ``PYPARDISO_MKL_RT`` variable at the library the ``mkl``
    wheel installs makes that a plain load. Intel OpenMP threads spin for 200 ms after each
    parallel region by default, taking a core from ARPACK between solves and from other processes
    on a shared machine; ``KMP_BLOCKTIME=0`` (unless set already) puts them to sleep at once.
    """
    if "PYPARDISO_MKL_RT" not in os.environ:
        found = sorted(glob.glob(os.path.join(sys.prefix, "lib", "libmkl_rt.so*")))
        if found:
            os.environ["PYPARDISO_MKL_RT"] = found[0]
    os.environ.setdefault("KMP_BLOCKTIME", "0")
    try:
        import pypardiso
    except (ImportError, OSError):
        return None
    return pypardiso


class PardisoFactor:
    """MKL PARDISO Cholesky factorisation (mtype 2) of the upper triangle of ``a``.

    The factor lives in MKL's memory, released when this object is collected. Positive
    definiteness is checked on the pivots (``pardiso_getdiag``, iparm(56) = 1): PARDISO reports
    a negative pivot as error -4 but factorises a semi-definite matrix without complaint.

    PARDISO is called directly (:meth:`_call`) with the 1-based index arrays built once:
    ``PyPardisoSolver.factorize`` copies the matrix and ``solve`` re-checks and compares the
    whole matrix with the factorised one and rebuilds those arrays on every call, 1.5-2.5 ms of
    each ~11 ms solve at 60,744 DOF (measured), which a Lanczos run of ~100 solves repeats.
    The ordering is METIS's nested dissection run in parallel (iparm(2) = 3): the same fill as
    the sequential one (7.03M factor non-zeros at 60,744 DOF) and 0.17 s instead of 0.25 s of the
    analysis phase on 2 cores (measured). Every call runs on :func:`free_cores` MKL threads
    (at most MKL's own maximum), chosen when the factor is made.
    """

    backend = "pardiso"

    def __init__(self, a: sp.csr_matrix, filename: str):
        pypardiso = _pardiso_module()
        self.upper = sp.triu(a, format="csr")
        self.upper.sort_indices()
        solver = pypardiso.PyPardisoSolver(mtype=PARDISO_SPD)
        for number, value in ((1, 1),            # iparm(1): the values below, not defaults
                              (2, 3),            # METIS nested dissection, parallel (OpenMP)
                              (8, 0),            # no iterative refinement (exact Cholesky)
                              (12, 0),           # A x = b with A given by rows (CSR)
                              (56, 1)):          # keep the pivots for pardiso_getdiag
            solver.set_iparm(number, value)
        self.solver = solver
        self._threads = solver.libmkl.MKL_Set_Num_Threads_Local
        self._threads.argtypes, self._threads.restype = [ctypes.c_int], ctypes.c_int
        self.threads = min(free_cores(), int(solver.libmkl.MKL_Get_Max_Threads()))
        self._index = (self.upper.indptr.astype(np.int32) + 1,  # PARDISO's 1-based ia, ja
                       self.upper.indices.astype(np.int32) + 1)
        weakref.finalize(self, solver.free_memory, True)
        error = self._call(12, np.zeros((self.upper.shape[0], 1), order="F"))[1]
        if error == PARDISO_ZERO_PIVOT:
            raise massless_mechanism(filename)
        if error != 0:
            raise SolverError(card_message(
                f"MKL PARDISO failed to factorise K - sigma M (error {error}).",
                filename=filename,
                fix=f"set {ENV_VAR}=superlu to use scipy's SuperLU instead."))
        pivots, diag_elim = self._diagonals()
        if not np.all(np.isfinite(pivots)) or np.any(pivots <= PIVOT_RATIO * diag_elim):
            raise massless_mechanism(filename)

    def _call(self, phase: int, b: np.ndarray) -> tuple[np.ndarray, int]:
        """One PARDISO phase (12 analysis and factorisation, 33 solve) on the Fortran-ordered
        (n, k) right-hand sides ``b``; returns (x, PARDISO's error code)."""
        x = np.zeros_like(b)
        error = ctypes.c_int32(0)
        solver, one = self.solver, ctypes.byref(ctypes.c_int32(1))
        int_p = ctypes.POINTER(ctypes.c_int32)
        previous = self._threads(self.threads)   # this thread's MKL threads, restored below
        try:
            solver._mkl_pardiso(
                solver.pt.ctypes.data_as(ctypes.POINTER(solver._pt_type[0])), one, one,
                ctypes.byref(ctypes.c_int32(PARDISO_SPD)), ctypes.byref(ctypes.c_int32(phase)),
                ctypes.byref(ctypes.c_int32(self.upper.shape[0])), self.upper.data.ctypes.data_as(
                    ctypes.c_void_p), self._index[0].ctypes.data_as(int_p),
                self._index[1].ctypes.data_as(int_p), solver.perm.ctypes.data_as(int_p),
                ctypes.byref(ctypes.c_int32(1 if b.ndim == 1 else b.shape[1])),
                solver.iparm.ctypes.data_as(int_p), ctypes.byref(ctypes.c_int32(0)),
                b.ctypes.data_as(ctypes.c_void_p), x.ctypes.data_as(ctypes.c_void_p),
                ctypes.byref(error))
        finally:
            self._threads(previous)
        return x, error.value

    def _diagonals(self) -> tuple[np.ndarray, np.ndarray]:
        """(pivots, matrix diagonal), both (n,) in elimination order."""
        n = self.upper.shape[0]
        pivots, diag = np.zeros(n), np.zeros(n)
        error = ctypes.c_int32(0)
        self.solver.libmkl.pardiso_getdiag(
            self.solver.pt.ctypes.data_as(ctypes.c_void_p), pivots.ctypes.data_as(ctypes.c_void_p),
            diag.ctypes.data_as(ctypes.c_void_p), ctypes.byref(ctypes.c_int32(1)),
            ctypes.byref(error))
        if error.value != 0:
            raise SolverError(card_message(
                f"MKL PARDISO returned no pivots (error {error.value}).",
                fix=f"set {ENV_VAR}=superlu to use scipy's SuperLU instead."))
        return pivots, diag

    def solve(self, b: np.ndarray) -> np.ndarray:
        """x = A^-1 b for b of shape (n,) or (n, k): PARDISO's solve phase (33) on the factor."""
        x, error = self._call(33, np.asfortranarray(b, dtype=float))
        if error != 0:
            raise SolverError(card_message(
                f"MKL PARDISO failed to solve with its factor (error {error}).",
                fix=f"set {ENV_VAR}=superlu to use scipy's SuperLU instead."))
        return np.ascontiguousarray(x)


class SuperLUFactor:
    """Sparse LU of ``a`` without pivoting, ordered on the graph of DOF groups.

    A minimum-degree ordering of the grid connectivity (one node per grid), expanded to each
    grid's DOFs, gives less fill than ordering the DOF graph directly (about 16M instead of 21M
    factor non-zeros on a 60,000-DOF shell model) and costs a fraction of a second. Tiny pivots
    (relative to the matrix diagonal) mean a singular matrix: a massless mechanism.
    """

    backend = "superlu"

    def __init__(self, a: sp.csc_matrix, groups: np.ndarray | None, filename: str):
        self.perm = _grouped_ordering(a, groups)
        permuted = a[self.perm][:, self.perm].tocsc()
        try:
            self.lu = spla.splu(permuted, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                                options={"SymmetricMode": True})
        except RuntimeError:
            raise massless_mechanism(filename) from None
        pivots = np.abs(self.lu.U.diagonal())
        diag = np.abs(permuted.diagonal())[self.lu.perm_c]
        if not np.all(np.isfinite(pivots)) or np.any(pivots <= PIVOT_RATIO * diag):
            raise massless_mechanism(filename)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """x = A^-1 b for b of shape (n,) or (n, k).

        Column by column: SuperLU's own multi-right-hand-side solve is ~4x slower than a loop
        (1.18 s against 0.28 s for 12 columns at 60,744 DOF).
        """
        b = np.asarray(b, dtype=float)
        out = np.empty_like(b)
        if b.ndim == 1:
            out[self.perm] = self.lu.solve(b[self.perm])
        else:
            for j in range(b.shape[1]):
                out[self.perm, j] = self.lu.solve(b[self.perm, j])
        return out


def _grouped_ordering(a: sp.csc_matrix, groups: np.ndarray | None) -> np.ndarray:
    """Fill-reducing permutation of ``a`` computed on the graph of DOF groups (grids)."""
    n = a.shape[0]
    if groups is None:
        groups = np.arange(n)
    labels, inverse = np.unique(groups, return_inverse=True)
    coo = a.tocoo()
    graph = sp.csc_matrix((-np.ones(coo.nnz), (inverse[coo.row], inverse[coo.col])),
                          shape=(len(labels), len(labels)))
    graph.sum_duplicates()
    graph.data[:] = -1.0
    graph = graph + sp.diags(np.asarray(abs(graph).sum(axis=1)).ravel() + 1.0)  # dominant
    # SuperLU's perm_c[j] is the new position of column j.
    rank = spla.splu(graph.tocsc(), permc_spec="MMD_AT_PLUS_A",
                     options={"SymmetricMode": True}).perm_c
    return np.lexsort((np.arange(n), rank[inverse]))
