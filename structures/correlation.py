"""Test-analysis correlation: MAC, SEREP, mass orthogonality, cross-orthogonality, frequency errors.

Symbols follow the reference paper (Pak & Truong, X-56A, sec. II, eqs. 11-24):

- Phi_Aset (n_AD x m): analysis modes at the A-set DOFs, m = number of SEREP modes;
- Phi_M (n_MD x m), Phi_S: the rows of Phi_Aset at the measured (master) and other (slave) DOFs;
- Phi~_GM (n_MD x n): measured test shapes, n = number of test modes;
- Phi_g = (Phi_Aset^T Phi_Aset)^-1 Phi_Aset^T (eq. 13), M_A = Phi_g^T Phi_g (eq. 12);
- Phi_GAset = Phi_Aset (Phi_M^T Phi_M)^-1 Phi_M^T Phi~_GM (eq. 14), written Phi_Aset q with the
  *SEREP modal coordinates* q = Phi_M^+ Phi~_GM (m x n);
- orthogonality M = Phi_GAset^T M_A Phi_GAset (eq. 11), cross-orthogonality
  S = Phi_GAset^T M_A Phi_A (eq. 20), MAC (eq. 23), frequency error (f_i - f_iG)/f_iG (eq. 18).

No mass matrix is needed: M_A comes from the analysis modes. Because Phi_g Phi_Aset = I whenever
Phi_Aset has full column rank, eq. 11 reduces exactly to M = q^T q and eq. 20 to S = q^T (Phi_g Phi_A)
(= q^T restricted to the analysis modes when they are SEREP modes), so the n_AD x n_AD matrix M_A
is never formed (it is available from :func:`serep_mass` for small problems and tests).

Choices (settings in :class:`CorrelationSettings`):

- **A-set**: by default every DOF of the analysis modes Dataset (``a_set="all"``: 6 per grid, in
  the basic frame, constrained DOFs being zero rows, which do not change Phi_g); ``"translational"``
  keeps components 1-3. The A-set only decides on which DOFs the expanded shapes Phi_GAset live:
  M and S do not depend on it (identity above), which a test checks.
- **SEREP modes**: all analysis modes of the Dataset (rigid ones included, as the paper's 30), or
  the ``serep_modes`` listed. SEREP needs n_MD >= m and a well-conditioned Phi_M.
- **Normalisation** (stated once, used in eq. 11 and 20): every test mode is scaled to unit
  generalised mass in M_A and every analysis mode too:
  ``orthogonality_ij = M_ij / sqrt(M_ii M_jj)`` (NASA-STD-5002: diagonal normalised to 1.0) and
  ``cross_orthogonality_ij = S_ij / sqrt(M_ii (Phi_A^T M_A Phi_A)_jj)``; the denominator's second
  factor is 1 for SEREP modes. The sign is kept; |S_ij| <= 1 and S_ij^2 is the M_A-weighted MAC.
  The raw M_ii is reported as ``test_generalized_mass``.
- **MAC** (eq. 23) is computed on the measured DOFs only, test shape against analysis shape.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import xarray as xr

from structures.acceptance import DEFAULT_CRITERIA, evaluate_checks
from structures.common.errors import InputError
from structures.gvt import check_dofs_in_model, validate_gvt
from structures.modes import check_modes, elastic_index
from structures.pairing import pair_modes
from structures.suspension import without_suspension

_PAIR_BY = ("mac", "cross_orthogonality")
_A_SET = ("all", "translational")


@dataclass(frozen=True)
class CorrelationSettings:
    """Settings of :func:`correlate`.

    Attributes
    ----------
    pair_by : {"mac", "cross_orthogonality"}
        Metric the Hungarian pairing maximises (|S| for cross-orthogonality).
    a_set : {"all", "translational"}
        Analysis DOFs forming the SEREP A-set.
    serep_modes : tuple of int, optional
        Analysis mode numbers forming the SEREP basis; default all modes of the Dataset.
    max_condition : float
        Largest accepted 2-norm condition number of Phi_M (and Phi_Aset).
    """

    pair_by: str = "mac"
    a_set: str = "all"
    serep_modes: tuple[int, ...] | None = None
    max_condition: float = 1e8

    def __post_init__(self) -> None:
        if self.pair_by not in _PAIR_BY:
            raise InputError(f"correlation: pair_by={self.pair_by!r} is not one of {list(_PAIR_BY)}.")
        if self.a_set not in _A_SET:
            raise InputError(f"correlation: a_set={self.a_set!r} is not one of {list(_A_SET)}.")
        if self.serep_modes is not None and len(self.serep_modes) == 0:
            raise InputError("correlation: serep_modes is empty. Fix: list analysis mode numbers or "
                             "leave it None for all modes.")
        if not self.max_condition > 1:
            raise InputError(f"correlation: max_condition={self.max_condition} must be > 1.")


# ------------------------------------------------------------------------------------ array kernels
def mac(phi_g, phi_a) -> np.ndarray:
    """Modal assurance criterion, paper eq. 23.

    Parameters
    ----------
    phi_g : array_like, shape (n_dof, n_test)
        Test shapes at the measured DOFs.
    phi_a : array_like, shape (n_dof, n_fe)
        Analysis shapes at the same DOFs.

    Returns
    -------
    ndarray, shape (n_test, n_fe)
        MAC_ij = (Phi_iG^T Phi_j)^2 / ((Phi_iG^T Phi_iG)(Phi_j^T Phi_j)); 0 where a shape is zero.
    """
    phi_g, phi_a = np.asarray(phi_g, dtype=float), np.asarray(phi_a, dtype=float)
    num = (phi_g.T @ phi_a) ** 2                                           # eq. 23 numerator
    den = np.outer(np.sum(phi_g ** 2, axis=0), np.sum(phi_a ** 2, axis=0))  # eq. 23 denominator
    return np.divide(num, den, out=np.zeros_like(num), where=den > 0)


def serep_pseudo_inverse(phi, *, max_condition: float = 1e8, what: str = "Phi_Aset") -> np.ndarray:
    """Phi_g = (Phi^T Phi)^-1 Phi^T, paper eq. 13, by QR (no normal equations).

    Parameters
    ----------
    phi : array_like, shape (n_dof, m)
        Analysis modes at the A-set (eq. 13) or at the measured DOFs (eq. 14, Phi_M).
    max_condition : float
        Largest accepted condition number of ``phi``.
    what : str
        Name used in error messages.

    Returns
    -------
    ndarray, shape (m, n_dof)
    """
    phi = np.asarray(phi, dtype=float)
    n_dof, m = phi.shape
    if n_dof < m:
        raise InputError(f"SEREP: {what} has {n_dof} DOFs but {m} modes; SEREP needs at least as many "
                         "DOFs as modes (n_MD >= m). Fix: measure more DOFs or use fewer SEREP modes "
                         "(CorrelationSettings.serep_modes / --nmodes).")
    q, r = np.linalg.qr(phi)
    sv = np.linalg.svd(r, compute_uv=False)
    cond = sv[0] / sv[-1] if sv[-1] > 0 else np.inf
    if cond > max_condition:
        raise InputError(f"SEREP: {what} ({n_dof} DOFs x {m} modes) is rank-deficient (condition number "
                         f"{cond:.3g} > {max_condition:.3g}): the DOFs cannot tell some modes apart. "
                         "Fix: add sensors that see every SEREP mode or use fewer SEREP modes.")
    return scipy.linalg.solve_triangular(r, q.T)                          # eq. 13


def serep_mass(phi_aset, *, max_condition: float = 1e8) -> np.ndarray:
    """SEREP test-analysis mass matrix M_A = Phi_g^T Phi_g, paper eqs. 12-13.

    Parameters
    ----------
    phi_aset : array_like, shape (n_AD, m)

    Returns
    -------
    ndarray, shape (n_AD, n_AD)
        Dense; meant for small problems and checks (:func:`correlate` never forms it).
    """
    phi_g = serep_pseudo_inverse(phi_aset, max_condition=max_condition)
    return phi_g.T @ phi_g                                                 # eq. 12


def serep_coordinates(phi_m, phi_gm, *, max_condition: float = 1e8) -> np.ndarray:
    """SEREP modal coordinates of the test shapes, q = (Phi_M^T Phi_M)^-1 Phi_M^T Phi~_GM (eq. 14).

    Parameters
    ----------
    phi_m : array_like, shape (n_MD, m)
        Analysis modes at the measured DOFs.
    phi_gm : array_like, shape (n_MD, n)
        Measured shapes.

    Returns
    -------
    ndarray, shape (m, n)
    """
    return serep_pseudo_inverse(phi_m, max_condition=max_condition, what="Phi_M") @ np.asarray(phi_gm, float)


def significant_coordinates(phi_m, phi_gm, noise, sigmas: float, *,
                            max_condition: float = 1e8) -> np.ndarray:
    """SEREP modal coordinates (eq. 14) with those the measurement noise could make set to 0.

    With white noise of standard deviation sigma_j on every measured DOF of test shape j, the
    coordinate q_kj = (Phi_M^+ Phi~_GM)_kj has the standard deviation sigma_j |row k of Phi_M^+|
    (cov q_j = sigma_j^2 Phi_M^+ Phi_M^+^T). A mode the measured DOFs see little, relative to its
    generalised mass (a local mode of a mass hung on a joint), has a long row: noise alone gives
    it a coordinate that dominates every test shape's, and the cross-orthogonality (eq. 20) then
    reports the noise. Coordinates within ``sigmas`` standard deviations of 0 are set to 0.

    Parameters
    ----------
    phi_m : array_like, shape (n_MD, m)
        Analysis modes at the measured DOFs.
    phi_gm : array_like, shape (n_MD, n)
        Measured shapes.
    noise : array_like, shape (n,)
        Noise standard deviation per measured DOF of each test shape (in its units).
    sigmas : float
        Significance threshold in standard deviations.

    Returns
    -------
    ndarray, shape (m, n)
    """
    pinv = serep_pseudo_inverse(phi_m, max_condition=max_condition, what="Phi_M")
    q = pinv @ np.asarray(phi_gm, float)
    std = np.linalg.norm(pinv, axis=1)[:, None] * np.asarray(noise, float)[None, :]
    return np.where(np.abs(q) > sigmas * std, q, 0.0)


def serep_expand(phi_aset, master, phi_gm, *, max_condition: float = 1e8) -> np.ndarray:
    """Expand measured shapes to the A-set, paper eq. 14.

    Parameters
    ----------
    phi_aset : array_like, shape (n_AD, m)
    master : array_like of int, shape (n_MD,)
        Row of every measured DOF in ``phi_aset``.
    phi_gm : array_like, shape (n_MD, n)

    Returns
    -------
    ndarray, shape (n_AD, n)
        Phi_GAset = [Phi_M; Phi_S] (Phi_M^T Phi_M)^-1 Phi_M^T Phi~_GM.
    """
    phi_aset = np.asarray(phi_aset, dtype=float)
    q = serep_coordinates(phi_aset[np.asarray(master)], phi_gm, max_condition=max_condition)
    return phi_aset @ q                                                    # eq. 14


def orthogonality(q) -> tuple[np.ndarray, np.ndarray]:
    """Normalised mass orthogonality of test modes, paper eq. 11 with eqs. 12-14.

    Parameters
    ----------
    q : array_like, shape (m, n)
        SEREP modal coordinates of the test shapes.

    Returns
    -------
    ortho : ndarray, shape (n, n)
        M_ij / sqrt(M_ii M_jj) with M = Phi_GAset^T M_A Phi_GAset = q^T q.
    gmass : ndarray, shape (n,)
        The raw diagonal M_ii.
    """
    q = np.asarray(q, dtype=float)
    m_bar = q.T @ q                                                        # eq. 11 (Phi_g Phi_Aset = I)
    gmass = np.diagonal(m_bar).copy()
    scale = 1.0 / np.sqrt(gmass)
    return m_bar * scale[:, None] * scale[None, :], gmass


def cross_orthogonality(q, g) -> np.ndarray:
    """Normalised cross-orthogonality, paper eq. 20.

    Parameters
    ----------
    q : array_like, shape (m, n)
        SEREP modal coordinates of the test shapes.
    g : array_like, shape (m, n_fe)
        Phi_g Phi_A: SEREP coordinates of the analysis modes (columns of the identity for SEREP modes).

    Returns
    -------
    ndarray, shape (n, n_fe)
        S_ij / sqrt(M_ii (Phi_A^T M_A Phi_A)_jj) with S = Phi_GAset^T M_A Phi_A = q^T g.
    """
    q, g = np.asarray(q, dtype=float), np.asarray(g, dtype=float)
    s_bar = q.T @ g                                                        # eq. 20 (Phi_g Phi_Aset = I)
    return s_bar / np.sqrt(np.sum(q ** 2, axis=0))[:, None] / np.sqrt(np.sum(g ** 2, axis=0))[None, :]


def frequency_error(f_fe, f_test) -> np.ndarray:
    """Frequency error in percent, 100 (f_i - f_iG) / f_iG (paper eq. 18); shapes broadcast."""
    f_test = np.asarray(f_test, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return 100.0 * (np.asarray(f_fe, dtype=float) - f_test) / f_test   # eq. 18


def default_nmodes(gvt: xr.Dataset, n_rigid: int = 6) -> int:
    """Analysis modes to compute for pairing and SEREP: 2 x test modes + rigid modes, at most n_MD.

    Twice the test modes leaves the pairing room for interchanged and unmeasured modes; SEREP
    needs m <= n_MD.
    """
    return int(min(2 * gvt.sizes["mode"] + n_rigid, gvt.sizes["dof"]))


# ------------------------------------------------------------------------------------ Dataset level
def measured_dof_index(fe_modes: xr.Dataset, gvt: xr.Dataset) -> np.ndarray:
    """Position along ``fe_modes.dof`` of every GVT DOF; raises naming unknown grids/components.

    Returns
    -------
    ndarray of int, shape (n_MD,)
    """
    check_dofs_in_model(gvt, fe_modes["grid"].values)
    fe_key = fe_modes["grid"].values.astype(np.int64) * 10 + fe_modes["component"].values
    g_key = gvt["grid"].values.astype(np.int64) * 10 + gvt["component"].values
    order = np.argsort(fe_key, kind="stable")
    pos = np.searchsorted(fe_key[order], g_key)
    pos = np.minimum(pos, fe_key.size - 1)
    found = fe_key[order][pos] == g_key
    if not np.all(found):
        miss = [(int(k // 10), int(k % 10)) for k in g_key[~found]]
        raise InputError(f"GVT file {gvt.attrs.get('source') or '(arrays)'}: measured DOFs (grid, component) "
                         f"{miss[:20]} are not DOFs of the analysis modes. Fix: the modes Dataset must "
                         "carry all 6 components of every grid.")
    return order[pos]


def _serep_basis(fe_modes: xr.Dataset, settings: CorrelationSettings) -> xr.Dataset:
    if settings.serep_modes is None:
        return fe_modes
    wanted = np.asarray(settings.serep_modes)
    unknown = wanted[~np.isin(wanted, fe_modes["mode"].values)]
    if unknown.size:
        raise InputError(f"correlation: serep_modes {unknown.tolist()} are not analysis modes "
                         f"{fe_modes['mode'].values.tolist()}. Fix: list computed mode numbers.")
    return fe_modes.sel(mode=wanted)


def _prepare(fe_modes: xr.Dataset, gvt: xr.Dataset, settings: CorrelationSettings):
    """Validate; return measured-DOF index (n_MD,), A-set mask (n_dof,), SEREP basis (n_dof, m)."""
    validate_gvt(gvt)
    check_modes(fe_modes, where=f"analysis modes {fe_modes.attrs.get('deck', '')}".strip())
    index = measured_dof_index(fe_modes, gvt)
    comp = fe_modes["component"].values
    a_mask = np.ones(comp.size, bool) if settings.a_set == "all" else comp <= 3
    if not np.all(a_mask[index]):
        raise InputError("correlation: rotations were measured but a_set='translational'. Fix: use "
                         "a_set='all'.")
    return index, a_mask, _serep_basis(fe_modes, settings)["shape"].values.T


def expand_test_shapes(fe_modes: xr.Dataset, gvt: xr.Dataset,
                       settings: CorrelationSettings = CorrelationSettings()) -> xr.Dataset:
    """SEREP-expanded test shapes Phi_GAset on the A-set (paper eq. 14), in the modes layout.

    Returns
    -------
    xarray.Dataset
        ``frequency(mode)``, ``shape(mode, dof)`` on the A-set DOFs with the analysis Dataset's
        dof coordinates; ``mode`` holds the test mode numbers.
    """
    index, a_mask, basis = _prepare(fe_modes, gvt, settings)
    q = serep_coordinates(basis[index], gvt["shape"].values.T, max_condition=settings.max_condition)
    expanded = (basis[a_mask] @ q).T                                       # eq. 14
    fe_a = fe_modes.isel(dof=np.nonzero(a_mask)[0])
    coords = {k: v for k, v in fe_a.coords.items() if "dof" in v.dims}
    coords["mode"] = gvt["mode"].values
    return xr.Dataset({"frequency": (("mode",), gvt["frequency"].values, {"units": "Hz"}),
                       "shape": (("mode", "dof"), expanded)}, coords=coords,
                      attrs={"source": "SEREP expansion (Pak & Truong eq. 14)", "a_set": settings.a_set,
                             "gvt": gvt.attrs.get("source", ""), "deck": fe_modes.attrs.get("deck", "")})


def correlate(fe_modes: xr.Dataset, gvt: xr.Dataset, settings: CorrelationSettings = CorrelationSettings(),
              criteria=DEFAULT_CRITERIA, primary_modes=None) -> xr.Dataset:
    """Correlate analysis modes with GVT modes (paper sec. II.B-E and IV).

    Parameters
    ----------
    fe_modes : xarray.Dataset
        Analysis modes Dataset (``frequency(mode)``, ``shape(mode, dof)``, ``grid``/``component``).
    gvt : xarray.Dataset
        GVT Dataset (:mod:`structures.gvt`).
    settings : CorrelationSettings
    criteria : sequence of AcceptanceCriteria
        Acceptance checks (default MIL-STD-1540C and NASA-STD-5002 style).
    primary_modes : sequence of int, optional
        Primary test modes (others secondary); default all primary.

    Returns
    -------
    xarray.Dataset
        ``mac(test_mode, fe_mode)``, ``orthogonality(test_mode, test_mode_2)``,
        ``cross_orthogonality(test_mode, fe_mode)``, ``frequency_error(test_mode)`` [%],
        ``paired_fe_mode(test_mode)``, ``paired_fe_frequency``, ``paired_mac``, ``interchanged``,
        ``test_frequency``, ``test_damping``, ``test_generalized_mass``, optional ``test_name``,
        ``fe_frequency(fe_mode)``, and the pass/fail variables of
        :func:`structures.acceptance.evaluate_checks` on (check, test_mode). The pairing assigns
        elastic analysis modes only (:func:`structures.modes.elastic_index`; a rigid-body mode
        has no elastic test counterpart, and a poorly matched test mode would otherwise take one
        at 0 Hz, a 100 % frequency error), unless a test mode has zero frequency. Test modes
        that are suspension modes of a model with rigid-body modes (rigid-body motions at the
        sensors below the first elastic analysis frequency,
        :func:`structures.suspension.without_suspension`) are left out; attribute
        ``suspension_modes`` lists them.
    """
    gvt, hung = without_suspension(fe_modes, gvt)
    index, a_mask, basis = _prepare(fe_modes, gvt, settings)
    phi_fe = fe_modes["shape"].values.T                                    # Phi_A (all dofs x n_fe)
    phi_gm = gvt["shape"].values.T                                         # Phi~_GM (n_MD x n)
    q = serep_coordinates(basis[index], phi_gm, max_condition=settings.max_condition)
    lost = np.sum(q ** 2, axis=0) <= 1e-24 * np.sum(phi_gm ** 2, axis=0)
    if np.any(lost):
        raise InputError(f"GVT file {gvt.attrs.get('source') or '(arrays)'}: test modes "
                         f"{gvt['mode'].values[lost].tolist()} have no component in the span of the SEREP "
                         "modes at the measured DOFs. Fix: compute more analysis modes or check the shapes.")
    g = serep_pseudo_inverse(basis[a_mask], max_condition=settings.max_condition) @ phi_fe[a_mask]
    ortho, gmass = orthogonality(q)
    cross = cross_orthogonality(q, g)
    mac_m = mac(phi_gm, phi_fe[index])
    f_test, f_fe = gvt["frequency"].values, fe_modes["frequency"].values
    metric = mac_m if settings.pair_by == "mac" else np.abs(cross)
    elastic = elastic_index(fe_modes) if np.all(f_test > 0) else np.arange(f_fe.size)
    pairing = pair_modes(metric[:, elastic], f_test, f_fe[elastic])
    fe_index = elastic[pairing.fe_index]
    paired = fe_modes["mode"].values[fe_index]
    test_modes = gvt["mode"].values
    t, tf = ("test_mode",), ("test_mode", "fe_mode")
    ds = xr.Dataset(
        {"mac": (tf, mac_m, {"long_name": "MAC on the measured DOFs (eq. 23)"}),
         "orthogonality": (("test_mode", "test_mode_2"), ortho,
                           {"long_name": "test-mode mass orthogonality, diagonal normalised to 1 (eq. 11)"}),
         "cross_orthogonality": (tf, cross,
                                 {"long_name": "cross-orthogonality, unit generalised masses (eq. 20)"}),
         "frequency_error": (t, frequency_error(f_fe[fe_index], f_test),
                             {"units": "%", "long_name": "100 (f_FE - f_GVT) / f_GVT (eq. 18)"}),
         "paired_fe_mode": (t, paired),
         "paired_fe_frequency": (t, f_fe[fe_index], {"units": "Hz"}),
         "paired_mac": (t, mac_m[np.arange(test_modes.size), fe_index]),
         "interchanged": (t, pairing.interchanged),
         "test_frequency": (t, f_test, {"units": "Hz"}),
         "test_damping": (t, gvt["damping"].values, {"units": "1", "long_name": "zeta"}),
         "test_generalized_mass": (t, gmass, {"long_name": "raw Phi_GAset^T M_A Phi_GAset diagonal"}),
         "fe_frequency": (("fe_mode",), f_fe, {"units": "Hz"})},
        coords={"test_mode": test_modes, "test_mode_2": test_modes, "fe_mode": fe_modes["mode"].values})
    if "name" in gvt:
        ds["test_name"] = (t, gvt["name"].values.astype(object))
    if all(c in gvt.coords and c in fe_modes.coords for c in ("x", "y", "z")):
        offset = np.sqrt(sum((gvt[c].values - fe_modes[c].values[index]) ** 2 for c in ("x", "y", "z")))
        ds.attrs["max_sensor_offset"] = float(offset.max())  # GVT node vs model grid position
    swaps = ", ".join(f"{test_modes[i]}<->{test_modes[j]}" for i, j in pairing.swaps)
    ds.attrs.update({
        "pair_by": settings.pair_by, "a_set": settings.a_set, "n_serep_modes": basis.shape[1],
        "n_measured_dofs": int(index.size), "n_aset_dofs": int(a_mask.sum()),
        "interchanges": swaps or "none",
        "suspension_modes": ", ".join(str(int(m)) for m in hung["mode"].values) or "none",
        "normalisation": "orthogonality_ij = M_ij/sqrt(M_ii M_jj); cross_orthogonality_ij = "
                         "S_ij/sqrt(M_ii (Phi_A^T M_A Phi_A)_jj); M_A = SEREP mass (eqs. 12-13)",
        "gvt": gvt.attrs.get("source", ""), "deck": fe_modes.attrs.get("deck", ""),
        "fe_source": fe_modes.attrs.get("source", ""),
        "reference": "Pak & Truong, X-56A GVT-validated FE model, eqs. 11-24"})
    checks = evaluate_checks(ds, criteria, primary_modes)
    out = xr.merge([ds, checks], combine_attrs="override")
    out.attrs.update(checks.attrs)
    return out
