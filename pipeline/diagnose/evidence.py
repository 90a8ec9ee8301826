"""Evidence of a model-test disagreement: the residual vector with known scales.

The residual of one configuration is built from entries of unit variance when the model is right
(the ``Reference`` fixes how, once per configuration, from the nominal model):

- **frequency** of every paired mode j: (f_j - f_jG) / f_jG / sigma_fj (paper eq. 18 without the
  100), sigma_fj^2 = frequency_noise^2 + the variance the nominal scatter causes
  (:mod:`pipeline.diagnose.scatter`: every section quantity and CONM2 scattering independently
  by model_scatter);
- **shape** of every paired mode j (when the test has shapes): the test shape t_j scaled to unit
  RMS over the sensors, minus the least-squares fit of the analysis shape a_j,
  d_j = t_j - (a_j . t_j / a_j . a_j) a_j, written in the nominal model's modal coordinates at the
  sensors, q_j = A0^+ d_j (A0: the nominal rigid modes and the elastic modes of the test band,
  :func:`residual_basis`, at the sensors, each at unit RMS; SEREP, paper eq. 14; q_kj is the
  cross-orthogonality off-diagonal S_jk of eq. 20 in the sensors' metric). Entry k of q_j is
  divided by its standard deviation: sensor noise, sigma_nj^2 (A0^+ A0^+T)_kk, plus the mixing
  the nominal scatter causes: by first-order perturbation (modal expansion, Fox & Kapoor 1968)
  the coefficient of mode k in mode j is
  c_kj = -phi_k^T (dK - lambda_j dM) phi_j / (lambda_k - lambda_j)
  (:func:`pipeline.diagnose.scatter.scatter_effects`), times rho_k / rho_j for the unit-RMS
  scaling, capped at ``scatter.MIXING_CAP`` (close modes mix freely: the data cannot tell their
  combination from a model error). The own coordinate k = j is left out. d_j is orthogonal to
  a_j and turned to the sign of t_j's own coordinate, so neither shape's sign matters and
  q_kj ~ +c_kj rho_k / rho_j in the nominal modes' signs;
- **mass** properties present in the measured mass (the paper's J1..J10, eqs. 1-10): weight and
  inertias relative to the measured value, CG relative to the radius of gyration, each divided by
  its stated accuracy (:mod:`pipeline.diagnose.weighing`).

One property's error moves several modes together, so the modal entries are correlated: the
training modal entries are multiplied by the whitening W of their scatter covariance
(:func:`pipeline.diagnose.scatter.whitening`, generalised least squares), the mass entries are
independent. chi^2 = |r|^2 of that residual over the training modes, BIC and goodness of fit
from it: :mod:`pipeline.diagnose.fit_statistics`. The test modes are paired with analysis modes
by :mod:`pipeline.diagnose.pairing`.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Mapping

import numpy as np
import xarray as xr

from pipeline.diagnose.pairing import INVISIBLE, pair, report_pairing, seen_shapes
from pipeline.diagnose.scatter import scatter_effects, scatter_scales, whitening
from pipeline.diagnose.weighing import mass_residual, mass_scales
from structures.assembly import assemble
from structures.common.errors import InputError
from structures.correlation import (mac, measured_dof_index, orthogonality, serep_coordinates,
                                    serep_pseudo_inverse)
from structures.massprops import MassProperties, mass_properties
from structures.modal import compute_modes
from structures.model import FEModel
from structures.modes import elastic_index, rigid_index

#: A test mode whose part outside the analysis modes' span is this many times the median (the
#: pooled noise) has no counterpart in the model.
UNMATCHED_NOISE = 3.0
#: Fewest sensor DOFs outside the analysis modes' span for the out-of-span noise estimate.
MIN_NOISE_DOF = 5
#: The shape residual's basis holds every visible analysis mode up to this share above the highest
#: test frequency (a mode just above the band mixes into the top test modes like one inside it).
BAND_MARGIN = 0.1
#: A band mode within this many standard deviations of a test mode's frequency may be its
#: counterpart (:func:`partner_mixing`).
PARTNER_SIGMAS = 3.0
#: A band mode joins the basis when at least this share of its sensor shape (unit norm) lies
#: outside the span of the modes already in: one the sensors see as a combination of those only
#: inflates the coordinates' noise.
DISTINCT = 0.1
#: Largest off-diagonal of the test-mode orthogonality (SEREP, analysis mass) before the data
#: quality is questioned (NASA-STD-5002 style limit 0.10, doubled for noise: 0.2).
SELF_ORTHOGONALITY_LIMIT = 0.2


# ------------------------------------------------------------------------------------ kernels
def holdout_mask(n_modes: int, holdout: int, rotation: int = 0) -> np.ndarray:
    """Held-out modes: every ``holdout``-th of ``n_modes`` paired modes in frequency order.

    ``rotation`` (the configuration's position) moves the held-out positions down by one per
    configuration, so that with several configurations every mode trains in some configuration
    (an effect that moves one mode, e.g. a local joint mode, is then never hidden from the naming
    altogether), while each configuration keeps a held-out third to judge the gap on.

    Returns
    -------
    ndarray of bool, shape (n_modes,)
        True for held-out modes: positions holdout-1-r, 2 holdout-1-r, ... (0-based),
        r = rotation mod holdout.
    """
    if holdout < 2:
        raise InputError(f"diagnose: holdout = {holdout} must be >= 2 (every holdout-th mode is "
                         "held out). Fix: use 2 or more.")
    mask = np.zeros(n_modes, bool)
    mask[(holdout - 1 - rotation) % holdout::holdout] = True
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


def shape_residual(projector, test_shapes, analysis_shapes, scale, keep) -> np.ndarray:
    """Shape residual per mode: +-(A0^+ (t_j - alpha_j a_j))_k / scale_kj over the kept k, the
    sign that makes t_j's own (left-out) coordinate positive.

    Parameters
    ----------
    projector : array_like, shape (m, n_dof)
        A0^+ (paper eq. 13 on the sensors).
    test_shapes : array_like, shape (n_mode, n_dof)
        Test shapes at unit RMS.
    analysis_shapes : array_like, shape (n_mode, n_dof)
        Paired analysis shapes at the same DOFs (any scaling, any sign; zero for a mode the
        sensors do not see, :func:`pipeline.diagnose.pairing.seen_shapes`: alpha = 0).
    scale : array_like, shape (n_mode, m)
        Standard deviation of every coordinate.
    keep : array_like of bool, shape (n_mode, m)
        Coordinates kept: all but the mode's own.

    Returns
    -------
    ndarray, shape (n_mode, m - 1)
    """
    t, a = np.asarray(test_shapes, float), np.asarray(analysis_shapes, float)
    norm = np.sum(a * a, axis=1)
    alpha = np.divide(np.sum(a * t, axis=1), norm, out=np.zeros(norm.size),
                      where=norm > 0.0)                                     # least-squares scale
    d = t - alpha[:, None] * a
    projector = np.asarray(projector, float)
    keep = np.asarray(keep, bool)
    own = np.argmin(keep, axis=1)                                           # the left-out one
    turn = np.where((t @ projector.T)[np.arange(t.shape[0]), own] < 0.0, -1.0, 1.0)
    q = turn[:, None] * (d @ projector.T) / np.asarray(scale, float)        # eq. 14 coordinates
    return q[keep].reshape(q.shape[0], -1)


def self_orthogonality(phi_m, shapes) -> float:
    """Largest off-diagonal of the test modes' SEREP orthogonality (paper eq. 11, analysis mass).

    Parameters
    ----------
    phi_m : (n_MD, m) mass-normalised analysis modes at the sensors (Phi^T M Phi = I: any other
        column scaling changes the metric the off-diagonals are measured in).
    shapes : (n, n_MD) test shapes.
    """
    q = serep_coordinates(phi_m, np.asarray(shapes, float).T)
    ortho, _ = orthogonality(q)
    off = np.abs(ortho - np.diag(np.diag(ortho)))
    return float(off.max(initial=0.0))


def residual_basis(frequency, sensor_shapes, rigid, elastic, paired, f_top: float) -> np.ndarray:
    """Elastic analysis modes of the shape residual's basis A0: the paired ones and every other
    mode of the test band the sensors can tell from them.

    A test mode is a mixture of the analysis modes near its frequency (the nominal scatter mixes
    close modes freely), whichever of them the pairing picked. A band mode left out of A0 would
    alias onto the modes in it, whose coordinates have noise-level scales: on the X-56 blind
    study's 'none' seed 9 a test mode in a cluster of three analysis modes (20.5-20.8 Hz), paired
    with a 32 Hz mode, left one of the three out and had a shape chi^2 of 2808 though it lies in
    the cluster's span to the noise.

    Parameters
    ----------
    frequency : (n_fe,) analysis frequencies [Hz].
    sensor_shapes : (n_fe, n_dof) analysis shapes at the measured DOFs.
    rigid : (n_rigid,) positions of the rigid-body modes (always in A0).
    elastic : (n_el,) positions of the elastic modes.
    paired : (n_test,) positions of the paired modes (always in the basis).
    f_top : float
        Highest test frequency; the band runs to f_top (1 + ``BAND_MARGIN``).

    Returns
    -------
    ndarray of int, sorted
        Positions along ``mode``: the paired modes and, in frequency order while A0 (with the
        rigid modes) has fewer than n_dof - ``MIN_NOISE_DOF`` columns, every visible
        (:data:`pipeline.diagnose.pairing.INVISIBLE`) band mode whose unit-RMS sensor shape
        keeps at least ``DISTINCT`` of its norm outside the span of the columns already in A0.
    """
    f = np.asarray(frequency, float)
    a = np.asarray(sensor_shapes, float)
    rms = np.sqrt(np.mean(a ** 2, axis=1))
    visible = rms >= INVISIBLE * rms[elastic].max()
    chosen = [int(k) for k in paired]
    fixed = [int(k) for k in rigid] + chosen
    others = [int(k) for k in elastic
              if k not in chosen and visible[k] and f[k] <= f_top * (1.0 + BAND_MARGIN)]
    limit = a.shape[1] - MIN_NOISE_DOF
    for k in sorted(others, key=lambda k: f[k]):
        if len(fixed) >= limit:
            break
        q, _ = np.linalg.qr((a[fixed] / rms[fixed, None]).T)
        u = a[k] / np.linalg.norm(a[k])
        if np.linalg.norm(u - q @ (q.T @ u)) >= DISTINCT:
            chosen.append(k)
            fixed.append(k)
    return np.sort(np.asarray(chosen, int))


def partner_mixing(test_frequency, band_frequency, band_sigma, paired, mixing) -> np.ndarray:
    """Standard deviation of every modal coordinate of each test mode's shape residual, whichever
    of its possible partners the test mode is.

    A test mode's partners are its paired band mode and every band mode whose frequency is within
    ``PARTNER_SIGMAS`` standard deviations of the test frequency. Any of them could be the test
    mode's counterpart (the nominal pairing picks one of a cluster of close modes by shapes that
    the scatter mixes), so each coordinate gets the largest mixing standard deviation over the
    partners, and every partner's own coordinate the cap
    (:data:`pipeline.diagnose.scatter.MIXING_CAP`): the residual does not depend on which of them
    the nominal pairing chose.

    Parameters
    ----------
    test_frequency : (n_test,) Hz.
    band_frequency : (n_band,) nominal analysis frequencies of the basis's elastic modes [Hz].
    band_sigma : (n_band,) relative standard deviation of each band mode's frequency (noise and
        scatter).
    paired : (n_test,) position in the band of every test mode's nominal partner.
    mixing : (n_band, m) mixing standard deviations with each band mode as its own
        (:func:`pipeline.diagnose.scatter.scatter_scales`).

    Returns
    -------
    ndarray, shape (n_test, m)
    """
    f_t = np.asarray(test_frequency, float)[:, None]
    near = (np.abs(np.asarray(band_frequency, float)[None, :] / f_t - 1.0)
            <= PARTNER_SIGMAS * np.asarray(band_sigma, float)[None, :])
    near[np.arange(f_t.shape[0]), np.asarray(paired, int)] = True
    mixing = np.asarray(mixing, float)
    return np.max(np.where(near[:, :, None], mixing[None, :, :], 0.0), axis=1)


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
    projector : (m, n_dof) A0^+ (nominal rigid and band modes at the sensors, unit RMS), or None.
    shape_scale : (n_test, m) standard deviation of every modal coordinate of the shape residual.
    shape_keep : (n_test, m) bool, coordinates kept (all but the mode's own).
    frequency_sigma : (n_test,) relative standard deviation of every frequency.
    shape_sigma : (n_test,) sensor noise per DOF relative to the shape's RMS, or None.
    train : (n_test,) bool, modes used to fit (the others judge the gap only).
    measured_mass : {quantity: value}
    mass_scale : {quantity: standard deviation}
    nmodes : int, analysis modes computed.
    scatter_rows : (n_train_rows, n_g) the training modal entries (the frequencies, then the
        kept shape coordinates mode by mode) per standard deviation of every scatter group's
        error (:func:`scatter_rows`), or None.
    whitening : (n_train_rows, n_train_rows) W applied to those entries, or None (independent).
    scatter_modes : (d_frequency (n_g, n_test), d_mixing (n_g, n_test, m), scatter) of
        :func:`scatter_rows` for every test mode, from which :func:`with_training` derives
        ``scatter_rows`` and ``whitening`` for another training split; or None.
    """

    name: str
    test_mode: np.ndarray
    test_frequency: np.ndarray
    shapes: np.ndarray | None
    sensor_index: np.ndarray | None
    sensor_grid: np.ndarray | None
    sensor_component: np.ndarray | None
    projector: np.ndarray | None
    shape_scale: np.ndarray | None
    shape_keep: np.ndarray | None
    frequency_sigma: np.ndarray
    shape_sigma: np.ndarray | None
    train: np.ndarray
    measured_mass: Mapping
    mass_scale: Mapping
    nmodes: int
    scatter_rows: np.ndarray | None = None
    whitening: np.ndarray | None = None
    scatter_modes: tuple | None = None

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

    def vector(self, ref: Reference) -> np.ndarray:
        """Residual vector: the training modes' entries (``ref.train``) whitened by
        ``ref.whitening``, then the mass entries."""
        modal = np.concatenate([self.frequency[ref.train], self.shape[ref.train].ravel()])
        if ref.whitening is not None:
            modal = ref.whitening @ modal
        return np.concatenate([modal, self.mass])


def evaluate(ref: Reference, model: FEModel, modes: xr.Dataset | None = None,
             paired=None) -> Evaluation:
    """Modes of ``model`` (computed unless given), pairing (``paired`` (n_test,) kept when
    given) and residual entries against ``ref``.

    ``model`` is the user's model, whose grid point singularities
    :func:`pipeline.diagnose.preflight.preflight` warned of, or one with an effect added or its
    parameters changed, whose file name is still the user's deck: no table is warned here.
    """
    if modes is None:
        modes = compute_modes(model, ref.nmodes, system=assemble(model, warn=False))
    props = mass_properties(model)
    return evaluate_modes(ref, modes["frequency"].values, modes["shape"].values[:, ref.sensor_index]
                          if ref.has_shapes else None, props, modes=modes, paired=paired)


def evaluate_modes(ref: Reference, frequency, sensor_shapes, props: MassProperties, *,
                   modes: xr.Dataset | None = None, paired=None) -> Evaluation:
    """Residual entries from analysis frequencies (n_fe,) and sensor shapes (n_fe, n_dof).

    ``paired`` (n_test,) keeps a given pairing (the linearised screening keeps the nominal one);
    otherwise the modes are paired again (``modes`` then gives the rigid-body flags).
    """
    frequency = np.asarray(frequency, float)
    if ref.has_shapes:
        sensor_shapes = seen_shapes(sensor_shapes)
    if paired is None:
        paired = pair(ref, modes, sensor_shapes=sensor_shapes)
    f_err = (frequency[paired] - ref.test_frequency) / ref.test_frequency   # paper eq. 18 / 100
    r_f = f_err / ref.frequency_sigma
    if ref.has_shapes:
        r_s = shape_residual(ref.projector, ref.shapes, np.asarray(sensor_shapes)[paired],
                             ref.shape_scale, ref.shape_keep)
    else:
        r_s = np.zeros((ref.test_frequency.size, 0))
    r_m = mass_residual(props, ref.measured_mass, ref.mass_scale)
    return Evaluation(modes=modes, paired=np.asarray(paired), frequency=r_f, shape=r_s, mass=r_m,
                      props=props)


def build_reference(name: str, model: FEModel, gvt: xr.Dataset, measured_mass: Mapping | None,
                    modes: xr.Dataset, *,
                    frequency_noise: float, shape_noise_value: float | None, model_scatter: float,
                    holdout: int, nmodes: int, rotation: int = 0) -> tuple[Reference, dict]:
    """Preflight of one configuration: pairing on the nominal modes, noise, training split.

    Returns
    -------
    Reference
    dict
        Preflight facts: ``self_orthogonality`` (largest off-diagonal or None), ``shape_noise``
        (pooled: median of the modes' estimates, or None), ``unmatched`` (test modes whose shape
        lies mostly outside the analysis modes' span), ``paired_fe_mode``, ``mac`` (paired MAC
        or None).
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
    facts = {"self_orthogonality": None, "shape_noise": None, "mac": None, "unmatched": []}
    sensor_index = grid = comp = shapes = noise = None
    if has_shapes:
        sensor_index = measured_dof_index(modes, gvt)
        grid, comp = gvt["grid"].values, gvt["component"].values
        shapes = unit_rms(gvt["shape"].values)
        phi_all = modes["shape"].values[:, sensor_index].T
        m_noise = min(phi_all.shape[1], phi_all.shape[0] - MIN_NOISE_DOF)
        if shape_noise_value is None:
            n_rigid = rigid_index(modes).size
            if m_noise - n_rigid < f_test.size:
                raise InputError(f"configuration {name}: {phi_all.shape[0]} measured DOFs are too "
                                 f"few to estimate the shape noise of {f_test.size} modes (the "
                                 f"span of the {n_rigid} rigid-body and {f_test.size} lowest "
                                 f"elastic analysis modes must leave {MIN_NOISE_DOF} DOFs outside "
                                 "it, or the higher test modes count as noise). Fix: give "
                                 "[diagnose] shape_noise.")
            per_mode = shape_noise(phi_all[:, :m_noise], shapes)
            # pooled: a test mode the model lacks altogether (a local mode) would otherwise count
            # as all noise and hide its own residual
            noise = np.full(f_test.size, float(np.median(per_mode)))
            facts["unmatched"] = gvt["mode"].values[per_mode > UNMATCHED_NOISE * noise].tolist()
        else:
            noise = np.full(f_test.size, float(shape_noise_value))
        facts["shape_noise"] = float(np.median(noise))
    ref = Reference(name=name, test_mode=gvt["mode"].values, test_frequency=f_test, shapes=shapes,
                    sensor_index=sensor_index, sensor_grid=grid, sensor_component=comp,
                    projector=None, shape_scale=None, shape_keep=None,
                    frequency_sigma=np.full(f_test.size, float(frequency_noise)),
                    shape_sigma=noise, train=~holdout_mask(f_test.size, holdout, rotation),
                    measured_mass=measured, mass_scale=mass_scales(measured, mass_properties(model)), nmodes=nmodes)
    paired = report_pairing(ref, modes)
    facts["paired_fe_mode"] = modes["mode"].values[paired].tolist()
    elastic = elastic_index(modes)
    rigid = rigid_index(modes)
    f_fe = modes["frequency"].values
    phi_m = modes["shape"].values[:, sensor_index] if has_shapes else None
    band = (residual_basis(f_fe, phi_m, rigid, elastic, paired, f_test.max()) if has_shapes
            else np.sort(paired))
    own = np.searchsorted(band, paired)                                    # position in the band
    keep = np.concatenate([rigid, band])
    d_freq, d_mix = scatter_effects(model, modes["shape"].values.T, (2.0 * np.pi * f_fe) ** 2,
                                    band)
    inside = np.arange(band.size)
    if has_shapes:
        rho = np.sqrt(np.mean(phi_m[keep] ** 2, axis=1))
        a0 = phi_m[keep].T / rho                                            # unit RMS columns
        projector = serep_pseudo_inverse(a0, what="Phi_M (rigid and band modes)")    # eq. 13
        # every computed mode mixes in, seen in A0's coordinates: A0^+ sum_k c_kj a_k / rho_j
        # (a mode outside A0 aliases onto its columns; a column of A0 is its own coordinate)
        d_mix[:, inside, band] = 0.0
        with np.errstate(invalid="ignore"):
            d_mix = d_mix @ (projector @ phi_m.T).T / rho[rigid.size:][None, :, None]
    else:
        d_mix = d_mix[:, :, keep]
    d_mix[:, inside, rigid.size + inside] = np.inf                         # the own: free
    band_sd, band_mixing = scatter_scales(d_freq, d_mix, model_scatter)
    freq_sd = band_sd[own]
    mixing_sd = partner_mixing(f_test, f_fe[band], np.hypot(frequency_noise, band_sd), own,
                               band_mixing)
    ref = replace(ref, frequency_sigma=np.hypot(frequency_noise, freq_sd))
    if has_shapes:
        noise_sd = noise[:, None] * np.sqrt(np.sum(projector ** 2, axis=1))[None, :]
        scale = np.sqrt(noise_sd ** 2 + mixing_sd ** 2)
        keep_mask = np.ones(scale.shape, bool)
        keep_mask[np.arange(own.size), rigid.size + own] = False
        facts["mac"] = np.diag(mac(shapes.T, phi_m[paired].T)).tolist()
        try:
            # the mass-normalised modes: q^T q is then the orthogonality in the analysis mass
            facts["self_orthogonality"] = self_orthogonality(phi_m[keep].T, shapes)
        except InputError:
            facts["self_orthogonality"] = None
        ref = replace(ref, projector=projector, shape_scale=scale, shape_keep=keep_mask)
    ref = replace(ref, scatter_modes=(d_freq[:, own], d_mix[:, own], model_scatter))
    return with_training(ref, ref.train), facts


def with_training(ref: Reference, train) -> Reference:
    """``ref`` with the modes ``train`` (n_test,) bool used to fit, the others held out: its
    scatter rows (:func:`scatter_rows`) and whitening for them."""
    ref = replace(ref, train=np.asarray(train, bool))
    rows = scatter_rows(ref, *ref.scatter_modes)
    return replace(ref, scatter_rows=rows, whitening=whitening(rows))


def scatter_rows(ref: Reference, d_frequency, d_mixing, scatter: float) -> np.ndarray:
    """Training modal residual entries (in :meth:`Evaluation.vector`'s order) per standard
    deviation of every scatter group's error.

    A truth that differs from the model by the errors e_g has r_f,j = -(df_j / f_j) / sigma_fj
    and q_kj = +c_kj rho_k / rho_j / scale_kj (the shape residual turned to the sign of the test
    shape's own coordinate, :func:`shape_residual`) to first order, so the rows are those
    derivatives times ``scatter``.

    Parameters
    ----------
    ref : Reference, its scales set.
    d_frequency : (n_g, n_test) d(df_j / f_j) / d e_g of every test mode's partner
        (:func:`pipeline.diagnose.scatter.scatter_effects`).
    d_mixing : (n_g, n_test, m) d(c_kj rho_k / rho_j) / d e_g over the basis.
    scatter : float, standard deviation of every e_g.

    Returns
    -------
    ndarray, shape (n_rows, n_g)
    """
    train = ref.train
    rows = [-scatter * np.asarray(d_frequency)[:, train].T / ref.frequency_sigma[train, None]]
    if ref.has_shapes:
        mix = scatter * np.asarray(d_mixing)[:, train] / ref.shape_scale[train][None]
        rows.append(np.transpose(mix, (1, 2, 0))[ref.shape_keep[train]])     # mode by mode
    return np.concatenate(rows)
