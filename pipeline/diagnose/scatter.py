"""The nominal scatter's effect on the residual: its standard deviations and its correlation.

Scatter model (``DiagnoseSettings.model_scatter`` = s): every section quantity of every property
card (:data:`SCATTER_FIELDS`: a PBAR's A, I1, I2 and J, a PSHELL's T, ...) and every CONM2 (its
mass with its inertia) is off by an independent relative error e_g of standard deviation s; all
elements of one PID share their card's errors. Error e_g changes the stiffness and mass by
e_g dK_g and e_g dM_g, dK_g = dK / d ln q_g (the derivative of the element matrices with respect
to the logarithm of the quantity, by central differences: one quantity changes both K and M when
it carries mass, as A does). A property card without listed quantities scatters as a whole
(dK_g = K_p, dM_g = M_p). Moduli are not scattered: they are calibrated.

First-order perturbation (modal expansion, Fox & Kapoor 1968), with the modal matrices
B_g,kj = phi_k^T (dK_g - lambda_j dM_g) phi_j of the mass-normalised modes phi:

    d lambda_j = sum_g e_g B_g,jj,     c_kj = -sum_g e_g B_g,kj / (lambda_k - lambda_j),

so the relative frequency error is d lambda_j / (2 lambda_j) and the coefficient of mode k in the
unit-RMS shape of mode j is c_kj rho_k / rho_j (rho: RMS at the sensors). Each residual entry is a
sum over the same errors e_g: the entries are correlated, one property's error moving several
modes together. :func:`scatter_scales` gives their standard deviations (the residual's scales,
:mod:`pipeline.diagnose.evidence`) and :func:`whitening` the transformation that makes them
uncorrelated (generalised least squares, Aitken 1935).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from structures.assembly import element_matrices
from structures.model import FEModel, Property

#: Section quantities that scatter independently, per property card.
SCATTER_FIELDS = {"PBAR": ("A", "I1", "I2", "J"), "PBEAM": ("A", "I1", "I2", "J"),
                  "PROD": ("A", "J"), "PSHELL": ("T",), "PELAS": ("K",),
                  "PBUSH": ("K1", "K2", "K3", "K4", "K5", "K6")}
#: Relative step of the central difference of the element matrices (exact for the quantities
#: that enter linearly or quadratically, as A, I and J of a beam without shear flexibility).
STEP = 0.01
#: Largest standard deviation of a mixing coefficient (unit-RMS shapes): two modes closer than
#: the nominal scatter can mix in any proportion.
MIXING_CAP = 1.0
#: Smallest share of an entry's variance left uncorrelated (noise) in :func:`whitening`; an entry
#: whose first-order scatter variance exceeds 1 - FIRST_ORDER_FLOOR of its scale squared (close
#: modes, the mixing capped) is beyond the first-order model and is left independent.
FIRST_ORDER_FLOOR = 0.01

_FAMILIES = ("CBAR", "CBEAM", "CROD", "CELAS", "CMASS2", "CBUSH", "CQUAD4", "CTRIA3")


def _scatters(prop: Property | None, field: str) -> bool:
    """Whether ``prop`` (None: no property card) scatters its (nonzero) ``field``."""
    return (prop is not None and field in SCATTER_FIELDS.get(prop.card, ())
            and bool(prop.fields.get(field)))


def _scaled(model: FEModel, field: str, factor: float) -> FEModel:
    """``model`` with ``field`` of every card that scatters it multiplied by ``factor``."""
    props = {pid: (Property(pid, p.card, {**p.fields, field: p.fields[field] * factor})
                   if _scatters(p, field) else p)
             for pid, p in model.properties.items()}
    return replace(model, properties=props)


def _modal(phi_e, mat) -> np.ndarray:
    return np.einsum("eak,eab,ebj->ekj", phi_e, mat, phi_e)                 # phi_k^T X_e phi_j


def group_matrices(model: FEModel, phi) -> tuple[np.ndarray, np.ndarray, list]:
    """Modal matrices of every scatter group's stiffness and mass derivative.

    Parameters
    ----------
    model : FEModel
    phi : (6 n_grid, m) g-set basic-frame shapes (mass-normalised).

    Returns
    -------
    bk, bm : (n_g, m, m) phi^T dK_g phi and phi^T dM_g phi.
    labels : list of (card, id, quantity) per group (quantity ``"*"``: the whole card).
    """
    phi = np.asarray(phi, float)
    m = phi.shape[1]
    shapes = phi.reshape(-1, 6, m)
    families = [es for kind, es in model.elements.items() if kind in _FAMILIES]
    fields = sorted({f for p in model.properties.values()
                     for f in SCATTER_FIELDS.get(p.card, ()) if _scatters(p, f)})
    bk, bm, labels = [], [], []

    def add(gi, k_e, m_e, ids, mask, quantity, card=None):
        if not np.any(mask):
            return
        phi_e = shapes[gi[mask]].reshape(int(mask.sum()), -1, m)
        uniq, inverse = np.unique(np.asarray(ids)[mask], return_inverse=True)
        for x, out in ((k_e, bk), (m_e, bm)):
            summed = np.zeros((uniq.size, m, m))
            if x is not None:
                np.add.at(summed, inverse, _modal(phi_e, x[mask]))
            out.append(summed)
        labels.extend((card or _card(model, i), int(i), quantity) for i in uniq)

    def scattered(pid, field):
        return _scatters(model.properties.get(int(pid)), field)

    matrices = list(element_matrices(model))
    for (gi, k_e, m_e), es in zip(matrices, families):
        whole = np.array([not any(scattered(p, f) for f in fields) for p in es.pids], bool)
        add(gi, k_e, m_e, es.pids, whole, "*")
    for field in fields:
        plus = element_matrices(_scaled(model, field, 1.0 + STEP))
        minus = element_matrices(_scaled(model, field, 1.0 - STEP))
        for (gi, kp, mp), (_, km, mm), es in zip(plus, minus, families):
            dk = None if kp is None else (kp - km) / (2.0 * STEP)
            dm = None if mp is None else (mp - mm) / (2.0 * STEP)
            add(gi, dk, dm, es.pids, np.array([scattered(p, field) for p in es.pids], bool),
                field)
    if len(model.masses.eids):
        gi, _, m_e = matrices[-1]                                           # the CONM2s, last
        add(gi, None, m_e, model.masses.eids, np.ones(len(model.masses.eids), bool), "mass",
            "CONM2")
    if not bk:
        return np.zeros((0, m, m)), np.zeros((0, m, m)), []
    return np.concatenate(bk), np.concatenate(bm) * model.wtmass, labels


def _card(model: FEModel, pid) -> str:
    prop = model.properties.get(int(pid))
    return prop.card if prop is not None else "element"


def scatter_effects(model: FEModel, phi, lam, own) -> tuple[np.ndarray, np.ndarray]:
    """Change of every relative frequency and mixing coefficient per unit error of each group.

    Parameters
    ----------
    model : FEModel
    phi : (6 n_grid, m) g-set basic shapes of the modes (mass-normalised).
    lam : (m,) their eigenvalues.
    own : (n,) position among them of every mode j.

    Returns
    -------
    frequency : (n_g, n) d(df_j / f_j) / d e_g = B_g,jj / (2 lambda_j).
    mixing : (n_g, n, m) d c_kj / d e_g = -B_g,kj / (lambda_k - lambda_j); +-inf where
        lambda_k = lambda_j (the mode's own, and degenerate modes).
    """
    bk, bm, _ = group_matrices(model, phi)
    lam = np.asarray(lam, float)
    own = np.asarray(own, int)
    lam_j = lam[own]
    b = bk[:, :, own] - lam_j[None, None, :] * bm[:, :, own]             # B_g,kj (n_g, m, n)
    frequency = b[:, own, np.arange(own.size)] / (2.0 * lam_j)             # Fox & Kapoor 1968
    gap = lam[:, None] - lam_j[None, :]                                     # (m, n)
    with np.errstate(divide="ignore", invalid="ignore"):
        c = np.where(gap != 0.0, -b / gap, np.inf)
    return frequency, np.transpose(c, (0, 2, 1))


def scatter_scales(frequency, mixing, scatter: float) -> tuple[np.ndarray, np.ndarray]:
    """Standard deviations of the relative frequencies (n,) and mixing coefficients (n, m) when
    every group errs independently by ``scatter``, from their derivatives ``frequency``
    (n_g, n) and ``mixing`` (n_g, n, m) (:func:`scatter_effects`, the mixing maybe taken to other
    coordinates); the mixing is capped at :data:`MIXING_CAP` (not finite: the cap)."""
    freq = scatter * np.sqrt(np.sum(np.asarray(frequency) ** 2, axis=0))
    with np.errstate(invalid="ignore"):
        mix = scatter * np.sqrt(np.sum(np.asarray(mixing) ** 2, axis=0))
    return freq, np.minimum(np.nan_to_num(mix, nan=np.inf), MIXING_CAP)


def whitening(rows) -> np.ndarray:
    """Transformation W that makes residual entries with unit variances uncorrelated.

    Entry i, already divided by its standard deviation, is r_i = sum_g G_ig e_g + n_i: the
    groups' errors (unit variance, ``rows`` G holds the scatter s) and an independent remainder
    of variance Delta_i = 1 - sum_g G_ig^2 (the noise, and any scale above the first-order
    scatter). Its covariance is C = Delta + G G^T; with H = Delta^-1/2 G = U S V^T,

        W = (I - U diag(1 - 1 / sqrt(1 + S^2)) U^T) Delta^-1/2,     W C W^T = I,

    so |W r|^2 = r^T C^-1 r (Aitken 1935; the Woodbury form of C^-1). Entries whose first-order
    variance exceeds 1 - :data:`FIRST_ORDER_FLOOR` are beyond the first-order model (close
    modes): their rows of G are dropped and they stay independent.

    Parameters
    ----------
    rows : (n, n_g) G, finite or not (a non-finite row is beyond the first-order model).

    Returns
    -------
    ndarray, shape (n, n)
    """
    g = np.asarray(rows, float)
    finite = np.all(np.isfinite(g), axis=1)
    load = np.where(finite, np.sum(np.where(finite[:, None], g, 0.0) ** 2, axis=1), np.inf)
    first_order = load <= 1.0 - FIRST_ORDER_FLOOR
    g = np.where(first_order[:, None], g, 0.0)
    inv_sd = 1.0 / np.sqrt(1.0 - np.where(first_order, load, 0.0))             # Delta^-1/2
    u, s, _ = np.linalg.svd(g * inv_sd[:, None], full_matrices=False)
    a = 1.0 - 1.0 / np.sqrt(1.0 + s ** 2)
    return (np.eye(g.shape[0]) - (u * a) @ u.T) * inv_sd[None, :]
