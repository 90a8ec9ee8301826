"""Validated inputs of a flutter solution: modal matrices and structural damping.

The solver only needs the modal mass M_hh, stiffness K_hh, optional viscous damping B_hh and the
structural damping description; how they were made (our modes, Nastran's F06/OP2) does not matter.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from structures.common.errors import InputError

DAMPING_KINDS = ("hysteretic", "viscous")


@dataclass(frozen=True)
class StructuralDamping:
    """Structural damping g (g = 2 * zeta), constant or as a table versus frequency.

    Parameters
    ----------
    g : float
        Constant structural damping g_s, added to the table value.
    frequency, table_g : tuple of float
        A damping table in g units versus Hz (Nastran TABDMP1 with TYPE=G); linear interpolation,
        held constant beyond its ends.
    kind : {"hysteretic", "viscous"}
        ``"hysteretic"``: i * g * K_hh (DESIGN.md section 3); in the p-k iteration it enters as its
        equivalent viscous matrix g(f) K_hh / omega at the root's current frequency omega (exact for
        harmonic motion), and it is dropped for zero-frequency roots which have no such equivalent.
        ``"viscous"``: modal viscous damping b_j = g(f_j) omega_j m_j at each in-vacuo mode
        (Nastran's treatment of SDAMP/TABDMP1 in modal flutter), i.e.
        B_s = M Phi diag(g_j omega_j) Phi^T M with mass-normalised in-vacuo modes Phi.
    """

    g: float = 0.0
    frequency: tuple = ()
    table_g: tuple = ()
    kind: str = "hysteretic"

    def __post_init__(self):
        if self.kind not in DAMPING_KINDS:
            raise InputError(f"StructuralDamping: unknown kind {self.kind!r}. Fix: use one of "
                             f"{DAMPING_KINDS}.")
        f = tuple(float(x) for x in self.frequency)
        gt = tuple(float(x) for x in self.table_g)
        if len(f) != len(gt):
            raise InputError(f"StructuralDamping: table has {len(f)} frequencies but {len(gt)} g "
                             "values. Fix: give one g per frequency (TABDMP1 x, y pairs).")
        if len(f) > 1 and np.any(np.diff(f) <= 0):
            raise InputError(f"StructuralDamping: table frequencies {f} must increase. "
                             "Fix: sort the TABDMP1 pairs by frequency.")
        if not np.isfinite(self.g) or not np.all(np.isfinite(gt)):
            raise InputError("StructuralDamping: g must be finite. Fix: check the damping table.")
        object.__setattr__(self, "frequency", f)
        object.__setattr__(self, "table_g", gt)
        object.__setattr__(self, "g", float(self.g))

    def at(self, f_hz: np.ndarray) -> np.ndarray:
        """Damping g at frequencies ``f_hz`` (Hz), shape as ``f_hz``."""
        f_hz = np.asarray(f_hz, dtype=float)
        tab = np.interp(f_hz, self.frequency, self.table_g) if self.frequency else 0.0
        return self.g + tab

    @property
    def is_zero(self) -> bool:
        """True if no structural damping is defined."""
        return self.g == 0.0 and not any(self.table_g)


@dataclass(frozen=True)
class ModalSystem:
    """Modal (generalized) structural matrices of a flutter problem.

    Parameters
    ----------
    mass, stiffness : ndarray, shape (n, n)
        Generalized mass M_hh and stiffness K_hh (real).
    damping : ndarray, shape (n, n), optional
        Viscous generalized damping B_hh.
    structural : StructuralDamping
        Structural damping (constant g_s or a table, hysteretic or modal viscous).
    modes : tuple of int, optional
        Mode ids (default 1..n); they label the ``mode`` dimension of eigenvectors.
    """

    mass: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray | None = None
    structural: StructuralDamping = field(default_factory=StructuralDamping)
    modes: tuple | None = None

    def __post_init__(self):
        M = np.array(self.mass, dtype=float, copy=True)
        K = np.array(self.stiffness, dtype=float, copy=True)
        n = M.shape[0] if M.ndim == 2 else -1
        B = np.zeros_like(M) if self.damping is None else np.array(self.damping, dtype=float, copy=True)
        for name, A in (("mass", M), ("stiffness", K), ("damping", B)):
            if A.ndim != 2 or A.shape != (n, n):
                raise InputError(f"ModalSystem: {name} matrix has shape {A.shape}, expected square "
                                 f"({n}, {n}). Fix: pass M_hh, K_hh, B_hh of the same modes.")
            if not np.all(np.isfinite(A)):
                raise InputError(f"ModalSystem: {name} matrix contains NaN/inf. Fix: check the "
                                 "modal solution that produced it.")
        try:
            np.linalg.cholesky(0.5 * (M + M.T))
        except np.linalg.LinAlgError:
            raise InputError("ModalSystem: the generalized mass matrix is not positive definite. "
                             "Fix: check the modes (massless or duplicated modes).") from None
        modes = tuple(range(1, n + 1)) if self.modes is None else tuple(int(m) for m in self.modes)
        if len(modes) != n:
            raise InputError(f"ModalSystem: {len(modes)} mode ids for {n} modes. Fix: one id per mode.")
        for A in (M, K, B):
            A.setflags(write=False)
        object.__setattr__(self, "mass", M)
        object.__setattr__(self, "stiffness", K)
        object.__setattr__(self, "damping", B)
        object.__setattr__(self, "modes", modes)

    @property
    def n(self) -> int:
        """Number of modes."""
        return self.mass.shape[0]

    def in_vacuo(self) -> tuple[np.ndarray, np.ndarray]:
        """In-vacuo circular frequencies and mass-normalised modes, ascending frequency.

        Returns
        -------
        omega : ndarray, shape (n,)
            sqrt(max(lambda, 0)) of K phi = lambda M phi.
        phi : ndarray, shape (n, n)
            Columns are the modes, phi^T M phi = I.
        """
        lam, phi = sla.eigh(0.5 * (self.stiffness + self.stiffness.T), 0.5 * (self.mass + self.mass.T))
        return np.sqrt(np.maximum(lam, 0.0)), phi

    @property
    def hysteretic(self) -> bool:
        """True if structural damping is given and enters as i g K (hysteretic kind)."""
        return (not self.structural.is_zero) and self.structural.kind == "hysteretic"

    def viscous_damping(self) -> np.ndarray:
        """All viscous damping, shape (n, n): B_hh plus the modal viscous structural damping when
        the structural damping is of the viscous kind (:meth:`viscous_structural`)."""
        if (not self.structural.is_zero) and self.structural.kind == "viscous":
            return self.damping + self.viscous_structural()
        return self.damping.copy()

    def viscous_structural(self) -> np.ndarray:
        """Modal viscous structural damping B_s = M Phi diag(g_j omega_j) Phi^T M, shape (n, n)."""
        omega, phi = self.in_vacuo()
        g = self.structural.at(omega / (2 * np.pi))
        Mphi = self.mass @ phi
        return Mphi @ np.diag(g * omega) @ Mphi.T  # b_j = g_j omega_j m_j (Nastran modal damping)
