"""K(x), M(x) and their design derivatives by sub-assembly of the elements the variables change.

**Sub-assembly.** With the a-set map of the start design (u_basic = R T u_a, ``TR``), K(x) =
K_rest + sum_g TR^T K_g(x) TR over the groups g of elements changed by the same set of variables
(:func:`structures.design.element_groups`); K_rest = K(x0) - sum_g TR^T K_g(x0) TR is built once
(same for M and the rigid-body mass M0 = D^T M_gg D of the mass properties). The a-set partition
(SPC, rigid elements, AUTOSPC) is the start design's; a design that changed it would need a full
re-assembly.

**Polynomial groups.** Most tunable fields enter the element matrices as polynomials of low degree
in the field values: A, I1, I2, J, K, E, G, CONM2 values linearly (E A, E I, G J, rho A products are
multilinear), PSHELL T as T (membrane A = T G1, transverse shear S = (TS/T) T G3, mass rho T) and
T^3 (bending D = (12I/T^3) T^3/12 G2), T^2 with a MID4 coupling (QRG PSHELL). A group whose
variables v have degrees d_v (``DEGREE``, default 1) is therefore written in the ratios
u_v = x_v / x0_v as

    K_g(x) = sum_alpha C_alpha prod_v u_v^alpha_v,   0 <= alpha_v <= d_v,

the C_alpha found once from the group assembled on the tensor grid of d_v + 1 Chebyshev points per
variable in u_v in [0.6, 1.4] (an exact interpolation of a polynomial of that degree), the terms
below 1e-9 of the largest dropped (T and T^3 remain for a skin thickness alone) and the rest
refitted by least squares. The fit is checked against one more assembly at a point off the grid,
and before the grid is sampled, along each variable's line through it (a few assemblies). A group
whose matrices are not such a polynomial fails a check by far more than the round-off tolerance
``CHECK_TOL`` and is re-assembled at every design instead, its derivatives then central differences
of step 1e-4 |x_i| (truncation (h_i / x_i)^2 ~ 1e-8). Examples: a tuned MAT1 E whose G stays fixed
(given, or completed by the reader at the start value): the CQUAD4 membrane, condensed over its
incompatible modes, is then rational in E / G; Timoshenko shear factors; pinned ends condensing
coupled terms.

Element matrices enter as flat value arrays (:func:`structures.assembly.element_matrices`) mapped to
the a-set entries by a fixed sparse operator (the reduction TR^T A TR of each element entry), so a
re-assembled group costs its element routines and one sparse product; entries that are zero at
every sample (rotary mass, uncoupled terms) are structural zeros and stay out of the pattern.

For polynomial groups K(x), M(x) are sums of stored coefficient arrays on a fixed sparsity pattern
(no element is recomputed), and dK/dx_i = sum_alpha alpha_i C_alpha u^(alpha - e_i) / x0_i is exact.
"""
from __future__ import annotations

import itertools

import numpy as np
import scipy.sparse as sp

from structures.assembly import assemble, element_matrices
from structures.design import DesignSpace, apply_design, element_groups
from structures.frames import rigid_offset
from structures.modal import rigid_body_basis
from structures.model import FEModel

STEP = 1e-4
#: polynomial degree of the element matrices in a field's value (default 1)
DEGREE = {("PSHELL", "T"): 3}
MAX_TERMS = 64          # tensor-grid size above which a group is re-assembled instead
CHECK_TOL = 1e-10       # fit check: max |K_fit - K| <= CHECK_TOL max |K| (same for M, M0)
DROP_TOL = 1e-9         # terms whose coefficients are below DROP_TOL max |K| are dropped
CHUNK = 1 << 18         # raw element-matrix entries reduced at a time (_reduction)


def _csc_keys(a: sp.spmatrix):
    """Sorted int64 keys col * n + row of the stored entries of ``a`` (canonical CSC) and values."""
    a = a.tocsc()
    a.sum_duplicates()
    cols = np.repeat(np.arange(a.shape[1], dtype=np.int64), np.diff(a.indptr))
    return cols * a.shape[0] + a.indices.astype(np.int64), a.data


def _on_pattern(keys: np.ndarray, a: sp.spmatrix) -> np.ndarray:
    """Values of ``a`` at the entries ``keys`` (a sorted superset of its pattern)."""
    k, data = _csc_keys(a)
    out = np.zeros(keys.size)
    out[np.searchsorted(keys, k)] = data
    return out


def _pattern(keys: np.ndarray, n: int):
    """(indices, indptr) of the CSC (n, n) matrix with exactly the entries ``keys``, in their order."""
    index = np.int32 if max(n, keys.size) < np.iinfo(np.int32).max else np.int64
    indptr = np.r_[0, np.cumsum(np.bincount(keys // n, minlength=n))].astype(index)
    return (keys % n).astype(index), indptr


def _from_keys(pattern, values, n) -> sp.csc_matrix:
    """CSC (n, n) with ``values`` on a pattern of :func:`_pattern` (index arrays copied)."""
    return sp.csc_matrix((values, pattern[0].copy(), pattern[1].copy()), shape=(n, n))


def _reduction(rows, cols, tr):
    """Keys of TR^T A TR and the operator P with (TR^T A TR).data = P @ a for A = coo(a, rows, cols).

    Every g-set entry (r, c) adds a TR[r, p] TR[c, q] to the a-set entry (p, q). The products are
    formed ``CHUNK`` entries at a time (the index temporaries of a 20,000-DOF shell group would
    otherwise take ~300 MB); P is built column by column (raw entry by raw entry, the order they
    are formed in), so no sort beyond the one that numbers the keys.
    """
    n = tr.shape[1]
    key, value, count = [], [], []
    for lo in range(0, max(rows.size, 1), CHUNK):
        ta, tb = tr[rows[lo:lo + CHUNK]], tr[cols[lo:lo + CHUNK]]
        na_t, nb_t = np.diff(ta.indptr), np.diff(tb.indptr)
        c = na_t * nb_t
        entry = np.repeat(np.arange(c.size), c)
        local = np.arange(c.sum()) - np.repeat(np.cumsum(c) - c, c)
        nb_e = nb_t[entry]
        ia = ta.indptr[entry] + local // nb_e
        ib = tb.indptr[entry] + local % nb_e
        key.append(tb.indices[ib].astype(np.int64) * n + ta.indices[ia])
        value.append(ta.data[ia] * tb.data[ib])
        count.append(c)
    keys, inverse = np.unique(np.concatenate(key), return_inverse=True)
    indptr = np.r_[0, np.cumsum(np.concatenate(count))]
    op = sp.csc_matrix((np.concatenate(value), inverse.ravel(), indptr),
                       shape=(keys.size, rows.size)).tocsr()
    return keys, op


def _restrict(keys, op, used):
    """Drop the raw entries not ``used`` from a reduction operator, and the keys left empty."""
    op = (op @ sp.diags(used.astype(float))).tocsr()
    op.eliminate_zeros()
    rows = np.diff(op.indptr) > 0
    return keys[rows], op[rows]


class _Group:
    """Elements changed by one set of variables: raw element-matrix values and their reduction.

    ``values(x)`` gives the element matrices of the group at x as flat arrays (the order of
    :func:`structures.assembly.element_matrices`); ``k_op @ k``, ``m_op @ m`` are the a-set
    entries ``k_keys``, ``m_keys`` of TR^T K_gg TR, TR^T M_gg TR; ``m0(m)`` is D^T M_gg D.
    Polynomial groups also carry ``k``, ``m``, ``m0`` (:class:`_Polynomial`, a-set data).
    """

    def __init__(self, variables, sub: FEModel, owner: "SubAssembly"):
        self.variables, self.sub, self.owner = np.asarray(variables), sub, owner
        k_rc, m_rc = [], []
        for gi, k, m in element_matrices(sub, owner.mass):
            dofs = (6 * gi[:, :, None] + np.arange(6)).reshape(len(gi), -1)
            for mat, out in ((k, k_rc), (m, m_rc)):
                if mat is not None:
                    out.append((np.broadcast_to(dofs[:, :, None], mat.shape).ravel(),
                                np.broadcast_to(dofs[:, None, :], mat.shape).ravel()))
        index = np.int32 if 6 * len(owner.xyz) < np.iinfo(np.int32).max else np.int64
        k_rc = tuple(np.concatenate([a[i] for a in k_rc]).astype(index) if k_rc
                     else np.zeros(0, index) for i in (0, 1))
        self.m_rc = tuple(np.concatenate([a[i] for a in m_rc]).astype(index) if m_rc
                          else np.zeros(0, index) for i in (0, 1))
        self.k_keys, self.k_op = _reduction(*k_rc, owner.tr)
        self.m_keys, self.m_op = _reduction(*self.m_rc, owner.tr)
        self.k = self.m = self.m0 = None

    def values(self, x):
        """Flat element stiffness and mass values (mass times WTMASS) at design x."""
        ks, ms = [], []
        for _, k, m in element_matrices(apply_design(self.sub, self.owner.space, x), self.owner.mass):
            if k is not None:
                ks.append(k.ravel())
            if m is not None:
                ms.append(m.ravel())
        cat = lambda a: np.concatenate(a) if a else np.zeros(0)  # noqa: E731
        return cat(ks), cat(ms) * self.sub.wtmass

    def m0_of(self, m) -> np.ndarray:
        """D^T M_gg D (6, 6) of flat mass values."""
        ng = self.owner.d.shape[0]
        mg = sp.csr_matrix((m, self.m_rc), shape=(ng, ng))
        return self.owner.d.T @ (mg @ self.owner.d)

    def fit(self) -> bool:
        """Fit the polynomial (module docstring); False when a check point rejects it.

        Cheap rejection first: along each variable, the others at their first node, the matrices
        must be a polynomial of the variable's degree (checked at one more point on that line), so
        a group that is not polynomial costs a few assemblies, not the whole grid.
        """
        space = self.owner.space
        degree = [max(DEGREE.get((r.card, r.field), 1) for r in space.variables[v].fields)
                  for v in self.variables]
        nodes = [_chebyshev(d) for d in degree]
        check = 1.0 + 0.15 * np.sin(1.7 * np.arange(1, len(degree) + 1))
        exps = np.array(list(itertools.product(*[range(d + 1) for d in degree])), int)
        samples = _Samples(self)

        def rejects(points, value_at, vander, mono):
            """True when the interpolant through ``points`` misses the value at the check point."""
            for i in range(3):
                *grid, value = samples(list(points) + [value_at], i)
                grid = np.array(grid)
                scale = max(np.abs(grid).max(initial=0.0), np.abs(value).max(initial=0.0), 1e-300)
                coef = np.linalg.solve(vander, grid)
                if np.abs(mono @ coef - value).max(initial=0.0) > CHECK_TOL * scale:
                    return True
            return False

        ok = len(exps) <= MAX_TERMS
        base = [n[0] for n in nodes]
        for j in np.argsort(degree, kind="stable") if ok else []:
            line = [tuple(base[:j] + [t] + base[j + 1:]) for t in nodes[j]]
            off = tuple(base[:j] + [check[j]] + base[j + 1:])
            powers = np.arange(degree[j] + 1)
            if rejects(line, off, nodes[j][:, None] ** powers, check[j] ** powers):
                ok = False
                break
        points = [tuple(u) for u in itertools.product(*nodes)] if ok else [tuple(np.ones(len(degree)))]
        samples.add(points)
        # element-matrix entries that are zero at every sample (rotary mass of shells and bars,
        # uncoupled terms) are structural zeros: kept out of the patterns
        self.k_keys, self.k_op = _restrict(self.k_keys, self.k_op, samples.used[0])
        self.m_keys, self.m_op = _restrict(self.m_keys, self.m_op, samples.used[1])
        if not ok:
            return False
        vander = np.prod(np.array(points)[:, None, :] ** exps[None, :, :], axis=2)   # (npoint, nterm)
        mono = np.prod(check[None, :] ** exps, axis=1)
        fits = []
        for i in range(3):
            *grid, value = samples(points + [tuple(check)], i)
            grid = np.array(grid)
            scale = max(np.abs(grid).max(initial=0.0), 1e-300)
            coef = np.linalg.inv(vander) @ grid
            keep = np.abs(coef).max(axis=1, initial=0.0) > DROP_TOL * scale
            coef = np.linalg.pinv(vander[:, keep]) @ grid                  # least squares refit
            if np.abs(mono[keep] @ coef - value).max(initial=0.0) > CHECK_TOL * scale:
                return False
            fits.append((exps[keep], samples.expand(coef, i)))
        self.k = _Polynomial(self.variables, fits[0][0], (self.k_op @ fits[0][1].T).T)
        self.m = _Polynomial(self.variables, fits[1][0], (self.m_op @ fits[1][1].T).T)
        self.m0 = _Polynomial(self.variables, fits[2][0], fits[2][1].reshape(-1, 6, 6))
        return True


class _Samples:
    """Flat (K, M, M0) values of one group at sample designs, stored on their non-zero entries.

    A fit holds every sample of its group at once, and most raw element-matrix entries of a shell
    group are structural zeros (rotary mass, uncoupled terms: 52 % of the skin stiffness entries
    of the 20,000-DOF benchmark). Each sample is therefore stored on ``used[i]``, the union of the
    entries of matrix i non-zero in some sample so far; the stored samples are padded with zeros
    when a new one adds entries. Entries outside ``used`` are zero in every sample, so fits and
    checks on the stored entries equal those on the full arrays.
    """

    def __init__(self, group: _Group):
        self.group = group
        self.used = None          # [(nk,), (nm,), (36,)] bool
        self.stored = {}          # ratios u (tuple) -> [k, m, m0] on ``used``

    def __call__(self, points, i: int) -> list:
        """Values of matrix i (0: K, 1: M, 2: M0) on ``used[i]`` at each ratio tuple of ``points``."""
        self.add(points)
        return [self.stored[u][i] for u in points]

    def add(self, points):
        """Sample the group at the ratio tuples ``points`` not sampled yet (each once)."""
        space = self.group.owner.space
        for u in points:
            if u in self.stored:
                continue
            x = space.x0.copy()
            x[self.group.variables] *= np.asarray(u)
            k, m = self.group.values(x)
            full = (k, m, self.group.m0_of(m).ravel())
            if self.used is None:
                self.used = [np.zeros(a.size, bool) for a in full]
            for i, a in enumerate(full):
                grown = self.used[i] | (a != 0)
                if grown.sum() > self.used[i].sum():
                    at = np.flatnonzero(self.used[i][grown])        # old entries among the grown
                    for values in self.stored.values():
                        padded = np.zeros(at.size + np.count_nonzero(grown & ~self.used[i]))
                        padded[at] = values[i]
                        values[i] = padded
                    self.used[i] = grown
            self.stored[u] = [a[used] for a, used in zip(full, self.used)]

    def expand(self, values, i: int) -> np.ndarray:
        """(nterm, n_i) full-length rows of (nterm, used_i) values (zeros elsewhere)."""
        out = np.zeros((values.shape[0], self.used[i].size))
        out[:, self.used[i]] = values
        return out


def _chebyshev(degree: int) -> np.ndarray:
    """degree + 1 Chebyshev points in [0.6, 1.4]."""
    return 1.0 + 0.4 * np.cos(np.pi * (np.arange(degree + 1) + 0.5) / (degree + 1))


class _Polynomial:
    """sum_alpha C_alpha prod_v u_v^alpha_v over a group's variables (module docstring)."""

    def __init__(self, variables, exps, coef):
        self.variables, self.exps, self.coef = np.asarray(variables), exps, coef

    def at(self, u):
        """sum_alpha C_alpha u^alpha."""
        mono = np.prod(u[self.variables][None, :] ** self.exps, axis=1)
        return np.tensordot(mono, self.coef, axes=1)

    def derivative(self, u, j):
        """d/du_v of the polynomial for the group's j-th variable; None if it does not enter."""
        if not self.exps[:, j].any():
            return None
        e = self.exps.copy()
        a = e[:, j].astype(float)
        e[:, j] = np.maximum(e[:, j] - 1, 0)
        return np.tensordot(a * np.prod(u[self.variables][None, :] ** e, axis=1), self.coef, axes=1)


class SubAssembly:
    """K(x), M(x), M0(x) of one configuration by sub-assembly, and their derivatives.

    Parameters
    ----------
    model : FEModel
        The configuration's model at the start design.
    space : DesignSpace
    mass : {'deck', 'consistent', 'lumped'}

    Attributes
    ----------
    groups : list of _Group, the polynomial ones with ``k``, ``m``, ``m0`` set, the others
        re-assembled at every design (module docstring)
    """

    def __init__(self, model: FEModel, space: DesignSpace, mass: str = "deck"):
        self.model, self.space, self.mass = model, space, mass
        base = apply_design(model, space, space.x0)
        self.system = assemble(base, mass)
        self.tr = (self.system.rotation @ self.system.T).tocsr()
        self.xyz = model.grids.xyz
        # rigid-body motions about the origin, D (ng, 6): M0 = D^T M_gg D (structures.massprops)
        self.d = rigid_offset(self.xyz).reshape(-1, 6)
        self.groups = [_Group(v, sub, self) for v, sub in element_groups(base, space)]
        for g in self.groups:
            g.fit()
        n = self.tr.shape[1]
        self.k_keys = np.unique(np.concatenate([_csc_keys(self.system.K)[0]]
                                               + [g.k_keys for g in self.groups]))
        self.m_keys = np.unique(np.concatenate([_csc_keys(self.system.M)[0]]
                                               + [g.m_keys for g in self.groups]))
        self._k_pattern, self._m_pattern = _pattern(self.k_keys, n), _pattern(self.m_keys, n)
        for g in self.groups:
            g.k_pos = np.searchsorted(self.k_keys, g.k_keys)
            g.m_pos = np.searchsorted(self.m_keys, g.m_keys)
        k0, m0, m00 = self._group_data(space.x0)
        self.k_rest = _on_pattern(self.k_keys, self.system.K) - k0
        self.m_rest = _on_pattern(self.m_keys, self.system.M) - m0
        self.m0_rest = self.d.T @ (self.system.m_basic @ self.d) - m00
        self.n = n
        rb = np.asarray(rigid_body_basis(model, self.system))
        ra = rb[self.system.a_dofs]
        misfit = rb - self.system.T @ ra          # rigid motions the constraints forbid
        if np.abs(misfit).max() > 1e-9 * np.abs(rb).max():   # partially supported (e.g. SPCs)
            _, sv, vt = np.linalg.svd(misfit)
            ra = ra @ vt[np.sum(sv > 1e-9 * sv.max()):].T     # the motions they allow
        self.rigid = ra
        self.last_phi = None   # modes of the last design, a Lanczos start for the next one

    @property
    def direct(self) -> list:
        """The groups re-assembled at every design (not polynomial)."""
        return [g for g in self.groups if g.k is None]

    def _group_data(self, x):
        """Sum of every group's TR^T K TR, TR^T M TR on the patterns, and their M0, at x."""
        x = np.asarray(x, float)
        u = x / self.space.x0
        k = np.zeros(self.k_keys.size)
        m = np.zeros(self.m_keys.size)
        m0 = np.zeros((6, 6))
        for g in self.groups:
            if g.k is not None:
                k[g.k_pos] += g.k.at(u)
                m[g.m_pos] += g.m.at(u)
                m0 += g.m0.at(u)
            else:
                kv, mv = g.values(x)
                k[g.k_pos] += g.k_op @ kv
                m[g.m_pos] += g.m_op @ mv
                m0 += g.m0_of(mv)
        return k, m, m0

    def matrices(self, x):
        """K (na, na), M (na, na) sparse CSC and the rigid-body mass M0 (6, 6) about the origin at x."""
        k, m, m0 = self._group_data(x)
        return (_from_keys(self._k_pattern, self.k_rest + k, self.n),
                _from_keys(self._m_pattern, self.m_rest + m, self.n), self.m0_rest + m0)

    def derivatives(self, x):
        """dK/dx_i, dM/dx_i (lists of sparse CSC (na, na)) and dM0/dx_i (nvar, 6, 6).

        Exact for polynomial groups; central differences, step 1e-4 |x_i|, for re-assembled ones.
        """
        x = np.asarray(x, float)
        nvar = len(x)
        u = x / self.space.x0
        dk, dm = [[] for _ in range(nvar)], [[] for _ in range(nvar)]
        dm0 = np.zeros((nvar, 6, 6))
        for g in self.groups:
            for j, v in enumerate(g.variables):
                if g.k is not None:
                    scale = 1.0 / self.space.x0[v]
                    for poly, keys, out in ((g.k, g.k_keys, dk), (g.m, g.m_keys, dm)):
                        d = poly.derivative(u, j)
                        if d is not None:
                            out[v].append((keys, scale * d))
                    d0 = g.m0.derivative(u, j)
                    if d0 is not None:
                        dm0[v] += scale * d0
                    continue
                h = STEP * abs(x[v])
                xp, xm = x.copy(), x.copy()
                xp[v] += h
                xm[v] -= h
                (kp, mp), (km, mm) = g.values(xp), g.values(xm)
                dk[v].append((g.k_keys, g.k_op @ ((kp - km) / (2 * h))))
                dm[v].append((g.m_keys, g.m_op @ ((mp - mm) / (2 * h))))
                dm0[v] += g.m0_of((mp - mm) / (2 * h))
        return ([_sum_keys(p, self.n) for p in dk], [_sum_keys(p, self.n) for p in dm], dm0)


def _sum_keys(parts, n) -> sp.csc_matrix:
    """Sum of (keys, values) pieces as a CSC (n, n) matrix."""
    if not parts:
        return sp.csc_matrix((n, n))
    keys = np.concatenate([p[0] for p in parts])
    vals = np.concatenate([p[1] for p in parts])
    return sp.csc_matrix((vals, (keys % n, keys // n)), shape=(n, n))
