"""Evidence of a model-test disagreement: pairing, residual vector with known scales, chi^2, BIC.

The residual of one configuration is a vector whose entries are (nearly) independent with unit
variance when the model is right (the ``Reference`` fixes how it is built, once per configuration,
from the nominal model):

- **frequency** of every paired mode j: (f_j - f_jG) / f_jG / sigma_f (paper eq. 18 without the
  100), sigma_f^2 = frequency_noise^2 + (model_scatter / 2)^2: the test's own scatter plus the
  frequency scatter the nominal section and mass properties leave (f ~ sqrt(k / m) halves it);
- **shape** of every paired mode j (when the test has shapes): the test shape t_j scaled to unit
  RMS over the sensors, minus the least-squares fit of the analysis shape a_j,
  d_j = t_j - (a_j . t_j / a_j . a_j) a_j, written in the orthonormal basis Q0 (QR) of the nominal
  model's rigid and paired modes at the sensors: r_j = Q0^T d_j / sigma_sj. A first-order change
  of any mode is a combination of the analysis modes (modal expansion of dphi, Fox & Kapoor 1968),
  so Q0 keeps what a model change can explain; with white sensor noise the entries of Q0^T d_j are
  independent with the noise's variance. d_j is orthogonal to a_j, so the sign of a shape does not
  matter. It is the paper's cross-orthogonality off-diagonal (eq. 20) on the sensors' metric.
  sigma_sj^2 = noise_j^2 + model_scatter^2, noise_j the shape noise (settings or
  :func:`shape_noise`);
- **mass** properties present in the measured mass (the paper's J1..J10, eqs. 1-10): weight and
  inertias relative to the measured value, CG relative to the radius of gyration, each divided by
  its stated accuracy (``WEIGHT_ACCURACY``, ``CG_ACCURACY``, ``INERTIA_ACCURACY``).

chi^2 = |r|^2 over the training modes; BIC = chi^2 + p ln n (Schwarz 1978), n the number of
training residuals; a BIC difference above 10 is "very strong" evidence (Kass & Raftery 1995).
Goodness of fit: chi^2 below the ``GOF_QUANTILE`` quantile of the chi-square distribution with
n - p degrees of freedom.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Mapping

import numpy as np
import scipy.stats
import xarray as xr
from scipy.optimize import linear_sum_assignment

from structures.common.errors import InputError
from structures.correlation import mac, measured_dof_index, orthogonality, serep_coordinates
from structures.massprops import MassProperties, mass_properties
from structures.modal import compute_modes
from structures.model import FEModel
from structures.pairing import pair_modes

#: Weighing accuracy of the total weight (load cells, 0.5 %).
WEIGHT_ACCURACY = 0.005
#: CG accuracy as a fraction of the radius of gyration (0.5 %: a few mm on a 1 m radius).
CG_ACCURACY = 0.005
#: Accuracy of measured moments and products of inertia (pendulum / swing tests, 2 % of the
#: principal moments).
INERTIA_ACCURACY = 0.02
#: Goodness-of-fit quantile: chi^2 above the 99.9 % chi-square quantile is a misfit (1 false alarm
#: in 1000 fits of a right model).
GOF_QUANTILE = 0.999
#: Fewest sensor DOFs outside the analysis modes' span for the out-of-span noise estimate.
MIN_NOISE_DOF = 5
#: Largest off-diagonal of the test-mode orthogonality (SEREP, analysis mass) before the data
#: quality is questioned (NASA-STD-5002 style limit 0.10, doubled for noise: 0.2).
SELF_ORTHOGONALITY_LIMIT = 0.2
_INERTIA_NAMES = ("Ixx", "Iyy", "Izz", "Ixy", "Iyz", "Izx")
_DIAGONAL = {"Ixx": 0, "Iyy": 1, "Izz": 2}
_PRODUCTS = {"Ixy": (0, 1), "Iyz": (1, 2), "Izx": (2, 0)}


# ------------------------------------------------------------------------------------ kernels
def chi_square(r) -> float:
    """chi^2 = |r|^2 of a residual vector r (any shape) of unit-variance entries."""
    r = np.asarray(r, float)
    return float(np.sum(r * r))


def bic(chi2: float, n_params: int, n_data: int) -> float:
    """Bayesian information criterion chi^2 + p ln n (Schwarz 1978) for Gaussian residuals."""
    if n_data < 1:
        raise InputError("BIC: no residuals. Fix: give test modes (or measured mass properties).")
    return float(chi2 + n_params * np.log(n_data))                           # Schwarz 1978, eq. 2


def gof_limit(dof: int, quantile: float = GOF_QUANTILE) -> float:
    """chi^2 quantile for ``dof`` degrees of freedom (at least 1)."""
    return float(scipy.stats.chi2.ppf(quantile, max(int(dof), 1)))


def runs_test(values) -> float:
    """Two-sided p-value of the Wald-Wolfowitz runs test on the signs of ``values`` (in order).

    Few runs (long stretches of one sign along the modes) mean a structured residual. Normal
    approximation (Wald & Wolfowitz 1940): mu = 2 n+ n- / n + 1,
    var = (mu - 1)(mu - 2) / (n - 1). Returns 1.0 when one sign is absent.
    """
    signs = np.sign(np.asarray(values, float))
    signs = signs[signs != 0]
    n_pos, n_neg = int(np.sum(signs > 0)), int(np.sum(signs < 0))
    n = n_pos + n_neg
    if n_pos == 0 or n_neg == 0 or n < 3:
        return 1.0
    runs = 1 + int(np.sum(signs[1:] != signs[:-1]))
    mu = 2.0 * n_pos * n_neg / n + 1.0                                      # Wald & Wolfowitz 1940
    var = (mu - 1.0) * (mu - 2.0) / (n - 1.0)
    if var <= 0:
        return 1.0
    return float(2.0 * scipy.stats.norm.sf(abs(runs - mu) / np.sqrt(var)))


def holdout_mask(n_modes: int, holdout: int) -> np.ndarray:
    """Held-out modes: every ``holdout``-th of ``n_modes`` paired modes in frequency order.

    Returns
    -------
    ndarray of bool, shape (n_modes,)
        True for held-out modes: positions holdout-1, 2 holdout-1, ... (0-based).
    """
    if holdout < 2:
        raise InputError(f"diagnose: holdout = {holdout} must be >= 2 (every holdout-th mode is "
                         "held out). Fix: use 2 or more.")
    mask = np.zeros(n_modes, bool)
    mask[holdout - 1::holdout] = True
    return mask


def unit_rms(shapes) -> np.ndarray:
    """Shapes (n_mode, n_dof) scaled to unit RMS over the DOFs."""
    shapes = np.asarray(shapes, float)
    return shapes / np.sqrt(np.mean(shapes ** 2, axis=1, keepdims=True))


def shape_noise(phi_m, shapes) -> np.ndarray:
    """Noise of each test shape: its part outside the span of the analysis modes at the sensors.

    Parameters
    ----------
    phi_m : array_like, shape (n_dof, m)
        Analysis modes at the measured DOFs (m < n_dof).
    shapes : array_like, shape (n_mode, n_dof)
        Test shapes.

    Returns
    -------
    ndarray, shape (n_mode,)
        sigma_j = |(I - Q Q^T) t_j| / sqrt(n_dof - m) with t_j at unit RMS: the standard deviation
        of white noise per DOF relative to the shape's RMS (the part in the span is indistinguishable
        from a shape change, the part outside is noise; E|(I - QQ^T) e|^2 = (n_dof - m) sigma^2).
    """
    phi_m = np.asarray(phi_m, float)
    n_dof, m = phi_m.shape
    if n_dof - m < 1:
        raise InputError(f"shape noise: {n_dof} DOFs and {m} modes leave no DOF outside the span. "
                         "Fix: give shape_noise in the settings or compute fewer modes.")
    q, _ = np.linalg.qr(phi_m)
    t = unit_rms(shapes).T
    outside = t - q @ (q.T @ t)
    return np.sqrt(np.sum(outside ** 2, axis=0) / (n_dof - m))


def shape_residual(basis, test_shapes, analysis_shapes, sigma) -> np.ndarray:
    """Shape residual per mode: Q0^T (t_j - alpha_j a_j) / sigma_j, alpha_j the least-squares scale.

    Parameters
    ----------
    basis : array_like, shape (n_dof, n_b)
        Orthonormal columns Q0.
    test_shapes : array_like, shape (n_mode, n_dof)
        Test shapes at unit RMS.
    analysis_shapes : array_like, shape (n_mode, n_dof)
        Paired analysis shapes at the same DOFs (any scaling, any sign).
    sigma : array_like, shape (n_mode,)

    Returns
    -------
    ndarray, shape (n_mode, n_b)
    """
    t, a = np.asarray(test_shapes, float), np.asarray(analysis_shapes, float)
    alpha = np.sum(a * t, axis=1) / np.sum(a * a, axis=1)                   # least-squares scale
    d = t - alpha[:, None] * a
    return (d @ np.asarray(basis, float)) / np.asarray(sigma, float)[:, None]


def mass_scales(measured: Mapping, wtmass: float = 1.0) -> dict:
    """Stated standard deviation of every measured mass quantity (units of the quantity).

    ``wtmass`` (PARAM WTMASS) turns the measured weight into the mass units of the inertias.
    """
    weight = measured.get("weight")
    inertia = [abs(measured[k]) for k in ("Ixx", "Iyy", "Izz") if k in measured]
    scales = {}
    if weight is not None:
        scales["weight"] = WEIGHT_ACCURACY * weight
    i_ref = max(inertia) if inertia else None
    if any(k in measured for k in ("x_cg", "y_cg", "z_cg")):
        if weight is None or not inertia:
            raise InputError("diagnose: measured CG without weight and inertias: the CG accuracy is "
                             "stated relative to the radius of gyration. Fix: give weight and "
                             "inertia_cg in the measured-mass file too.")
    for key in ("x_cg", "y_cg", "z_cg"):
        if key in measured:
            # radius of gyration sqrt(I_max / m), m = weight x WTMASS (the inertias' mass units)
            scales[key] = CG_ACCURACY * np.sqrt(i_ref / (weight * wtmass))
    for key in _INERTIA_NAMES:
        if key in measured:
            scales[key] = INERTIA_ACCURACY * (abs(measured[key]) if key in _DIAGONAL else i_ref)
    return scales


def mass_residual(props: MassProperties, measured: Mapping, scales: Mapping) -> np.ndarray:
    """(model - measured) / scale for every measured quantity, in ``scales`` order."""
    values = props.as_dict()
    return np.array([(values[k] - measured[k]) / scales[k] for k in scales])


def self_orthogonality(phi_m, shapes) -> float:
    """Largest off-diagonal of the test modes' SEREP orthogonality (paper eq. 11, analysis mass)."""
    q = serep_coordinates(phi_m, np.asarray(shapes, float).T)
    ortho, _ = orthogonality(q)
    off = np.abs(ortho - np.diag(np.diag(ortho)))
    return float(off.max(initial=0.0))


def pair_frequency_only(test_frequency, fe_frequency) -> np.ndarray:
    """Nearest-frequency assignment: minimise sum |ln(f_fe / f_test)| (Hungarian method).

    Returns
    -------
    ndarray of int, shape (n_test,)
        Index of the analysis frequency paired with every test mode.
    """
    f_t = np.asarray(test_frequency, float)
    f_a = np.asarray(fe_frequency, float)
    if f_a.size < f_t.size:
        raise InputError(f"pairing: {f_t.size} test modes but only {f_a.size} elastic analysis "
                         "modes. Fix: compute more analysis modes (settings.nmodes).")
    cost = np.abs(np.log(np.maximum(f_a[None, :], 1e-300) / f_t[:, None]))
    rows, cols = linear_sum_assignment(cost)
    out = np.empty(f_t.size, int)
    out[rows] = cols
    return out


# ------------------------------------------------------------------------------ configuration
@dataclass(frozen=True)
class Reference:
    """The test side of one configuration and the fixed definition of its residual.

    Attributes
    ----------
    name : str
    test_mode : (n_test,) test mode numbers, in frequency order.
    test_frequency : (n_test,) Hz.
    shapes : (n_test, n_dof) test shapes at unit RMS, or None (frequency-only data).
    sensor_index : (n_dof,) position of every measured DOF along the modes Dataset's ``dof``.
    sensor_grid, sensor_component : (n_dof,) the measured DOFs.
    basis : (n_dof, n_b) orthonormal Q0 (nominal rigid + paired modes at the sensors), or None.
    frequency_sigma : float, relative.
    shape_sigma : (n_test,) relative to the shape's RMS, or None.
    train : (n_test,) bool, modes used to fit (the others judge the gap only).
    measured_mass : {quantity: value}
    mass_scale : {quantity: standard deviation}
    nmodes : int, analysis modes computed.
    """

    name: str
    test_mode: np.ndarray
    test_frequency: np.ndarray
    shapes: np.ndarray | None
    sensor_index: np.ndarray | None
    sensor_grid: np.ndarray | None
    sensor_component: np.ndarray | None
    basis: np.ndarray | None
    frequency_sigma: float
    shape_sigma: np.ndarray | None
    train: np.ndarray
    measured_mass: Mapping
    mass_scale: Mapping
    nmodes: int

    @property
    def has_shapes(self) -> bool:
        return self.shapes is not None


@dataclass(frozen=True)
class Evaluation:
    """A model's modes against one Reference.

    Attributes
    ----------
    modes : xarray.Dataset, the analysis modes.
    paired : (n_test,) index along ``modes.mode`` of the analysis mode paired with each test mode.
    frequency : (n_test,) residual entries of the frequencies.
    shape : (n_test, n_b) residual entries of the shapes (empty (n_test, 0) without shapes).
    mass : (n_q,) residual entries of the mass properties.
    props : MassProperties of the model.
    """

    modes: xr.Dataset
    paired: np.ndarray
    frequency: np.ndarray
    shape: np.ndarray
    mass: np.ndarray
    props: MassProperties

    def vector(self, train: np.ndarray) -> np.ndarray:
        """Residual vector over the modes in ``train`` (bool (n_test,)) plus the mass entries."""
        return np.concatenate([self.frequency[train], self.shape[train].ravel(), self.mass])


def elastic_index(modes: xr.Dataset) -> np.ndarray:
    """Positions along ``mode`` of the elastic (non rigid-body) modes."""
    if "rigid_motion" in modes.coords:
        return np.flatnonzero(modes["rigid_motion"].values == "")
    return np.arange(modes.sizes["mode"])


def pair(ref: Reference, modes: xr.Dataset, *, sensor_shapes=None) -> np.ndarray:
    """Pair the test modes with elastic analysis modes: MAC assignment, or nearest frequency.

    Returns
    -------
    ndarray of int, shape (n_test,)
        Index along ``modes.mode``.
    """
    elastic = elastic_index(modes)
    f_fe = modes["frequency"].values[elastic]
    if elastic.size < ref.test_frequency.size:
        raise InputError(f"configuration {ref.name}: {ref.test_frequency.size} test modes but only "
                         f"{elastic.size} elastic analysis modes. Fix: raise settings.nmodes.")
    if not ref.has_shapes:
        return elastic[pair_frequency_only(ref.test_frequency, f_fe)]
    if sensor_shapes is None:
        sensor_shapes = modes["shape"].values[:, ref.sensor_index]
    metric = mac(ref.shapes.T, sensor_shapes[elastic].T)                    # eq. 23
    return elastic[pair_modes(metric, ref.test_frequency, f_fe).fe_index]


def evaluate(ref: Reference, model: FEModel, modes: xr.Dataset | None = None) -> Evaluation:
    """Modes of ``model`` (computed unless given), pairing and residual entries against ``ref``."""
    if modes is None:
        modes = compute_modes(model, ref.nmodes)
    props = mass_properties(model)
    return evaluate_modes(ref, modes["frequency"].values, modes["shape"].values[:, ref.sensor_index]
                          if ref.has_shapes else None, props, modes=modes)


def evaluate_modes(ref: Reference, frequency, sensor_shapes, props: MassProperties, *,
                   modes: xr.Dataset | None = None, paired=None) -> Evaluation:
    """Residual entries from analysis frequencies (n_fe,) and sensor shapes (n_fe, n_dof).

    ``paired`` (n_test,) keeps a given pairing (the linearised screening keeps the nominal one);
    otherwise the modes are paired again (``modes`` then gives the rigid-body flags).
    """
    frequency = np.asarray(frequency, float)
    if paired is None:
        paired = pair(ref, modes, sensor_shapes=sensor_shapes)
    f_err = (frequency[paired] - ref.test_frequency) / ref.test_frequency   # paper eq. 18 / 100
    r_f = f_err / ref.frequency_sigma
    if ref.has_shapes:
        r_s = shape_residual(ref.basis, ref.shapes, np.asarray(sensor_shapes)[paired], ref.shape_sigma)
    else:
        r_s = np.zeros((ref.test_frequency.size, 0))
    r_m = mass_residual(props, ref.measured_mass, ref.mass_scale)
    return Evaluation(modes=modes, paired=np.asarray(paired), frequency=r_f, shape=r_s, mass=r_m,
                      props=props)


def build_reference(name: str, gvt: xr.Dataset, measured_mass: Mapping | None, modes: xr.Dataset, *,
                    frequency_noise: float, shape_noise_value: float | None, model_scatter: float,
                    holdout: int, nmodes: int, wtmass: float = 1.0) -> tuple[Reference, dict]:
    """Preflight of one configuration: pairing on the nominal modes, noise, training split.

    Returns
    -------
    Reference
    dict
        Preflight facts: ``self_orthogonality`` (largest off-diagonal or None), ``shape_noise``
        (median estimate or None), ``paired_fe_mode``, ``mac`` (paired MAC or None).
    """
    order = np.argsort(gvt["frequency"].values, kind="stable")
    gvt = gvt.isel(mode=order)
    f_test = gvt["frequency"].values.astype(float)
    if np.any(f_test <= 0):
        raise InputError(f"configuration {name}: GVT file {gvt.attrs.get('source', '')}: test modes "
                         f"{gvt['mode'].values[f_test <= 0].tolist()} have zero frequency; diagnose "
                         "pairs elastic modes only. Fix: drop the rigid-body modes from the GVT data.")
    has_shapes = "shape" in gvt
    measured = dict(measured_mass or {})
    facts = {"self_orthogonality": None, "shape_noise": None, "mac": None}
    sensor_index = grid = comp = shapes = basis = sigma_s = None
    if has_shapes:
        sensor_index = measured_dof_index(modes, gvt)
        grid, comp = gvt["grid"].values, gvt["component"].values
        shapes = unit_rms(gvt["shape"].values)
        phi_all = modes["shape"].values[:, sensor_index].T
        m_noise = min(phi_all.shape[1], phi_all.shape[0] - MIN_NOISE_DOF)
        if shape_noise_value is None:
            if m_noise < f_test.size:
                raise InputError(f"configuration {name}: {phi_all.shape[0]} measured DOFs are too "
                                 f"few to estimate the shape noise of {f_test.size} modes. Fix: give "
                                 "[diagnose] shape_noise.")
            noise = shape_noise(phi_all[:, :m_noise], shapes)
        else:
            noise = np.full(f_test.size, float(shape_noise_value))
        facts["shape_noise"] = float(np.median(noise))
        sigma_s = np.sqrt(noise ** 2 + model_scatter ** 2)
    ref = Reference(name=name, test_mode=gvt["mode"].values, test_frequency=f_test, shapes=shapes,
                    sensor_index=sensor_index, sensor_grid=grid, sensor_component=comp, basis=None,
                    frequency_sigma=float(np.hypot(frequency_noise, model_scatter / 2.0)),
                    shape_sigma=sigma_s, train=~holdout_mask(f_test.size, holdout),
                    measured_mass=measured, mass_scale=mass_scales(measured, wtmass), nmodes=nmodes)
    paired = pair(ref, modes)
    facts["paired_fe_mode"] = modes["mode"].values[paired].tolist()
    if has_shapes:
        phi_m = modes["shape"].values[:, sensor_index]
        rigid = np.setdiff1d(np.arange(modes.sizes["mode"]), elastic_index(modes))
        keep = np.concatenate([rigid, paired])
        basis, _ = np.linalg.qr(phi_m[keep].T)
        facts["mac"] = np.diag(mac(shapes.T, phi_m[paired].T)).tolist()
        try:
            facts["self_orthogonality"] = self_orthogonality(phi_m[keep].T, shapes)
        except InputError:
            facts["self_orthogonality"] = None
        ref = replace(ref, basis=basis)
    return ref, facts
