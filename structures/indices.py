"""Performance indices of model tuning (paper sec. II, eqs. 1-24), each individually addressable,
with their gradients.

Per configuration, with n test modes (numbers t_1..t_n of the GVT Dataset) and the analysis modes
paired with them by the assignment on |cross-orthogonality| (mode tracking, recomputed at every
evaluation):

============================  ======================================  ===========  ========
index name                    definition                              paper        sense
============================  ======================================  ===========  ========
``C:mass:weight`` ...         ((W - W_G) / W_G)^2, x/y/z CG, I's      eqs. 1-10    <= eps
``C:orthogonality:ti-tj``     Mbar_ij^2, i < j (normalised eq. 11)    eq. 15       <= eps
``C:frequency:ti``            ((f_i - f_iG) / f_iG)^2                 eq. 18       <= eps
``C:cross_orthogonality:ti-tj``  Sbar_ij^2, i != j (eq. 20)           eq. 21       <= eps
``C:mac:ti``                  MAC_ii (eq. 23)                         eq. 24       >= eps
============================  ======================================  ===========  ========

Sbar_ij is the (normalised) cross-orthogonality of test mode i with the analysis mode paired with
test mode j, so its diagonal holds the pairs and every off-diagonal is well defined through mode
interchange. MAC is the one index where larger is better: as a constraint it reads MAC_ii >= eps and
as an objective term it enters with a minus sign (so a positive weight improves it). Where a mass
target is zero (e.g. y_G = 0 of a symmetric aircraft) eqs. 2-10 divide by zero; a reference value
(a length or an inertia) must then be given and is used as the denominator.

The SEREP quantities reuse :mod:`structures.correlation`: with q = Phi_M^+ Phi~_GM (eq. 14) the
orthogonality is Mbar = q^T q (eq. 11) and the cross-orthogonality Sbar = q^T (eq. 20, SEREP basis =
the analysis modes). Their gradients follow from d(Phi_M^+) = -Phi_M^+ dPhi_M Phi_M^+
+ (Phi_M^T Phi_M)^-1 dPhi_M^T (I - Phi_M Phi_M^+), vectorised over the design variables.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from structures.correlation import cross_orthogonality, mac, orthogonality, serep_coordinates
from structures.common.errors import InputError
from structures.massprops import properties_from_rigid_body_mass
from structures.pairing import pair_modes

MASS_QUANTITIES = ("weight", "x_cg", "y_cg", "z_cg", "Ixx", "Iyy", "Izz", "Ixy", "Iyz", "Izx")
KINDS = ("mass", "orthogonality", "frequency", "cross_orthogonality", "mac")


# ------------------------------------------------------------------------------- mass properties
def _skew(v):
    """(..., 3) -> (..., 3, 3) cross-product matrices."""
    v = np.asarray(v, float)
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2], out[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    out[..., 1, 0], out[..., 2, 0], out[..., 2, 1] = v[..., 2], -v[..., 1], v[..., 0]
    return out


def mass_quantities(m0, wtmass: float = 1.0, dm0=None):
    """The ten quantities of J1..J10 from the rigid-body mass M0 about the origin, and gradients.

    Parameters
    ----------
    m0 : (6, 6) rigid-body mass about the basic origin (M0 = D^T M_gg D)
    wtmass : float, PARAM WTMASS (weight = mass / WTMASS)
    dm0 : (nvar, 6, 6), optional

    Returns
    -------
    values : (10,) weight, x/y/z CG, Ixx, Iyy, Izz about the CG, products Ixy, Iyz, Izx (sum m x y)
    grad : (nvar, 10) or None
    """
    props = properties_from_rigid_body_mass(m0, wtmass=wtmass)
    d = props.as_dict()
    values = np.array([props.weight] + [d[k] for k in MASS_QUANTITIES[1:]])
    if dm0 is None:
        return values, None
    dm0 = np.asarray(dm0, float)
    mass, cg = props.mass, props.cg
    dmass = dm0[:, 0, 0]
    # M0[:3, 3:] = -m skew(cg): cg_x = s[2,1], cg_y = s[0,2], cg_z = s[1,0] with s = -M0[:3,3:]/m
    s = -m0[:3, 3:] / mass
    ds = -dm0[:, :3, 3:] / mass - s[None] * (dmass / mass)[:, None, None]
    dcg = np.stack([ds[:, 2, 1], ds[:, 0, 2], ds[:, 1, 0]], axis=1)
    sk, dsk = _skew(cg), _skew(dcg)
    # I_cg = I_ref - m skew(cg)^T skew(cg)
    di = (dm0[:, 3:, 3:] - dmass[:, None, None] * (sk.T @ sk)[None]
          - mass * (np.swapaxes(dsk, 1, 2) @ sk[None] + sk.T[None] @ dsk))
    grad = np.column_stack([dmass / wtmass, dcg, di[:, 0, 0], di[:, 1, 1], di[:, 2, 2],
                            -di[:, 0, 1], -di[:, 1, 2], -di[:, 2, 0]])
    return values, grad


# ------------------------------------------------------------------------------ correlation terms
@dataclass(frozen=True)
class CorrelationTerms:
    """Orthogonality, cross-orthogonality, frequency errors and MAC of paired modes, with gradients.

    Attributes
    ----------
    fe_index : (n,) analysis mode (0-based column) paired with each test mode
    interchanged : (n,) bool, test modes in an interchange (structures.pairing)
    ortho : (n, n) normalised Mbar (eq. 11); cross : (n, n) Sbar_ij = S(test i, paired FE of j)
    freq_error : (n,) (f_i - f_iG) / f_iG (fraction); fe_frequency : (n,) paired f_i [Hz]
    mac : (n,) MAC_ii
    d_ortho (nvar, n, n), d_cross (nvar, n, n), d_freq_error (nvar, n), d_mac (nvar, n): or None
    """

    fe_index: np.ndarray
    interchanged: np.ndarray
    ortho: np.ndarray
    cross: np.ndarray
    freq_error: np.ndarray
    fe_frequency: np.ndarray
    mac: np.ndarray
    d_ortho: np.ndarray | None = None
    d_cross: np.ndarray | None = None
    d_freq_error: np.ndarray | None = None
    d_mac: np.ndarray | None = None


def correlation_terms(phi_m, phi_gm, lam, f_test, *, n_rigid: int = 0, dphi_m=None, dlam=None,
                      fe_index=None) -> CorrelationTerms:
    """Paired correlation quantities of one configuration (eqs. 11, 14, 18, 20, 23) and gradients.

    Parameters
    ----------
    phi_m : (n_MD, m) analysis modes at the measured DOFs (SEREP basis = all m modes)
    phi_gm : (n_MD, n) measured shapes
    lam : (m,) eigenvalues (rad/s)^2; f_test : (n,) [Hz]
    n_rigid : int, leading rigid modes (never paired)
    dphi_m : (nvar, n_MD, m), dlam : (nvar, m), optional
    fe_index : (n,) optional fixed pairing; default the assignment on |Sbar| (mode tracking)
    """
    phi_m, phi_gm = np.asarray(phi_m, float), np.asarray(phi_gm, float)
    m = phi_m.shape[1]
    q = serep_coordinates(phi_m, phi_gm)                                   # eq. 14
    ortho, gmass = orthogonality(q)                                        # eq. 11
    cross_full = cross_orthogonality(q, np.eye(m))                         # eq. 20
    f_fe = np.sqrt(np.clip(lam, 0.0, None)) / (2 * np.pi)
    if fe_index is None:
        pairing = pair_modes(np.abs(cross_full[:, n_rigid:]), f_test, f_fe[n_rigid:])
        fe_index = pairing.fe_index + n_rigid
        interchanged = pairing.interchanged
    else:
        fe_index = np.asarray(fe_index)
        interchanged = np.zeros(fe_index.size, bool)
    n = fe_index.size
    rows = np.arange(n)
    cross = cross_full[:, fe_index]
    err = (f_fe[fe_index] - f_test) / f_test                               # eq. 18
    mac_ii = mac(phi_gm, phi_m)[rows, fe_index]                            # eq. 23 diagonal
    if dphi_m is None:
        return CorrelationTerms(fe_index, interchanged, ortho, cross, err, f_fe[fe_index], mac_ii)
    gram_inv = np.linalg.inv(phi_m.T @ phi_m)
    pinv = gram_inv @ phi_m.T
    resid = phi_gm - phi_m @ q
    # dq = -A+ dA q + (A^T A)^-1 dA^T r  (derivative of the pseudo-inverse, eq. 14)
    dq = (-np.einsum("mk,vkl,ln->vmn", pinv, dphi_m, q, optimize=True)
          + np.einsum("ml,vkl,kn->vmn", gram_inv, dphi_m, resid, optimize=True))
    dmbar = np.einsum("vki,kj->vij", dq, q)
    dmbar = dmbar + np.swapaxes(dmbar, 1, 2)                               # d(q^T q)
    ddiag = np.diagonal(dmbar, axis1=1, axis2=2) / gmass                   # dM_ii / M_ii
    d_ortho = (dmbar / np.sqrt(np.outer(gmass, gmass))[None]
               - 0.5 * ortho[None] * (ddiag[:, :, None] + ddiag[:, None, :]))
    qn = np.sqrt(gmass)
    qp = q[fe_index]                                                       # (n_j, n_i): q[p_j, i]
    dqp = dq[:, fe_index]
    dnorm = np.einsum("ki,vki->vi", q, dq) / qn                            # d||q_i||
    d_cross = (np.swapaxes(dqp, 1, 2) / qn[None, :, None]
               - qp.T[None] * (dnorm / qn ** 2)[:, :, None])
    f_p = f_fe[fe_index]
    with np.errstate(divide="ignore", invalid="ignore"):
        df = np.where(f_p > 0, dlam[:, fe_index] / (8 * np.pi ** 2 * f_p), 0.0)
    d_err = df / f_test
    a = phi_gm
    b = phi_m[:, fe_index]
    db = dphi_m[:, :, fe_index]
    ab, aa, bb = np.sum(a * b, axis=0), np.sum(a * a, axis=0), np.sum(b * b, axis=0)
    d_mac = (2 * ab * np.einsum("ki,vki->vi", a, db) / (aa * bb)
             - 2 * mac_ii * np.einsum("ki,vki->vi", b, db) / bb)
    return CorrelationTerms(fe_index, interchanged, ortho, cross, err, f_p, mac_ii,
                            d_ortho, d_cross, d_err, d_mac)


# ---------------------------------------------------------------------------------- the catalogue
@dataclass(frozen=True)
class IndexCatalogue:
    """Every performance index of one configuration, by name (module docstring).

    Attributes
    ----------
    config : str
    test_modes : (n,) test mode numbers
    names : tuple of str
    kind : (nidx,) one of KINDS; row, col : (nidx,) positions (test-mode positions, or the mass
        quantity for ``mass``; col -1 when unused); paper_k : (nidx,) the paper's index number k
    targets : (10,) measured mass quantities (NaN if not given); denominators : (10,)
    """

    config: str
    test_modes: np.ndarray
    names: tuple
    kind: np.ndarray
    row: np.ndarray
    col: np.ndarray
    paper_k: np.ndarray
    targets: np.ndarray
    denominators: np.ndarray

    @property
    def lower_is_better(self) -> np.ndarray:
        """False for MAC (eq. 24), True for the others."""
        return self.kind != "mac"


def build_catalogue(config: str, test_modes, mass_targets=None, mass_references=None) -> IndexCatalogue:
    """All indices of a configuration.

    Parameters
    ----------
    config : str
    test_modes : (n,) test mode numbers being tuned
    mass_targets : mapping {quantity: measured value} for quantities of MASS_QUANTITIES
    mass_references : mapping {quantity: denominator} for zero targets (e.g. a reference length)
    """
    mass_targets, mass_references = dict(mass_targets or {}), dict(mass_references or {})
    for key in list(mass_targets) + list(mass_references):
        if key not in MASS_QUANTITIES:
            raise InputError(f"configuration {config}: unknown mass quantity {key!r}; valid: "
                             f"{list(MASS_QUANTITIES)}.")
    targets = np.array([mass_targets.get(k, np.nan) for k in MASS_QUANTITIES], float)
    denom = np.array([mass_references.get(k, abs(mass_targets.get(k, np.nan)))
                      for k in MASS_QUANTITIES], float)
    bad = [k for k, t, d in zip(MASS_QUANTITIES, targets, denom) if np.isfinite(t) and not d > 0]
    if bad:
        raise InputError(f"configuration {config}: mass targets {bad} are zero, so eqs. 1-10 would "
                         "divide by zero. Fix: give a reference value (mass_references) for them.")
    modes = np.asarray(test_modes)
    n = modes.size
    names, kind, row, col, paper = [], [], [], [], []

    def add(name, k, r, c, number):
        names.append(f"{config}:{k}:{name}")
        kind.append(k)
        row.append(r)
        col.append(c)
        paper.append(number)

    for q, label in enumerate(MASS_QUANTITIES):
        if np.isfinite(targets[q]):
            add(label, "mass", q, -1, q + 1)                               # eqs. 1-10
    l_m = (n * n - n) // 2                                                 # eq. 16
    k = 11
    for i in range(n):
        for j in range(i + 1, n):
            add(f"{modes[i]}-{modes[j]}", "orthogonality", i, j, k)        # eq. 15
            k += 1
    for i in range(n):
        add(f"{modes[i]}", "frequency", i, -1, 11 + l_m + i)               # eq. 18
    k = 11 + l_m + n
    for i in range(n):
        for j in range(n):
            if i != j:
                add(f"{modes[i]}-{modes[j]}", "cross_orthogonality", i, j, k)   # eq. 21
                k += 1
    for i in range(n):
        add(f"{modes[i]}", "mac", i, -1, 11 + l_m + n + (n * n - n) + i)  # eq. 24
    return IndexCatalogue(config, modes, tuple(names), np.array(kind), np.array(row),
                          np.array(col), np.array(paper), targets, denom)


def index_values(cat: IndexCatalogue, mass_values, corr: CorrelationTerms, mass_grad=None):
    """Values J_k of every index of ``cat`` and, when the terms carry gradients, dJ_k/dx.

    Parameters
    ----------
    cat : IndexCatalogue
    mass_values : (10,) from :func:`mass_quantities`; mass_grad : (nvar, 10) or None
    corr : CorrelationTerms

    Returns
    -------
    values : (nidx,); grad : (nidx, nvar) or None
    """
    kind, r, c = cat.kind, cat.row, cat.col
    values = np.zeros(len(cat.names))
    with_grad = corr.d_ortho is not None and mass_grad is not None
    grad = np.zeros((len(cat.names), corr.d_ortho.shape[0])) if with_grad else None
    sel = kind == "mass"
    rel = (mass_values[r[sel]] - cat.targets[r[sel]]) / cat.denominators[r[sel]]
    values[sel] = rel ** 2                                                 # eqs. 1-10
    sel_o, sel_f = kind == "orthogonality", kind == "frequency"
    sel_s, sel_a = kind == "cross_orthogonality", kind == "mac"
    values[sel_o] = corr.ortho[r[sel_o], c[sel_o]] ** 2                    # eq. 15
    values[sel_f] = corr.freq_error[r[sel_f]] ** 2                         # eq. 18
    values[sel_s] = corr.cross[r[sel_s], c[sel_s]] ** 2                    # eq. 21
    values[sel_a] = corr.mac[r[sel_a]]                                     # eq. 24
    if with_grad:
        grad[sel] = (2 * rel / cat.denominators[r[sel]])[:, None] * mass_grad[:, r[sel]].T
        grad[sel_o] = (2 * corr.ortho[r[sel_o], c[sel_o]])[:, None] * corr.d_ortho[:, r[sel_o], c[sel_o]].T
        grad[sel_f] = (2 * corr.freq_error[r[sel_f]])[:, None] * corr.d_freq_error[:, r[sel_f]].T
        grad[sel_s] = (2 * corr.cross[r[sel_s], c[sel_s]])[:, None] * corr.d_cross[:, r[sel_s], c[sel_s]].T
        grad[sel_a] = corr.d_mac[:, r[sel_a]].T
    return values, grad
