"""Shell materials (MAT1, MAT2, MAT8) and PSHELL section stiffness.

A :class:`ShellSection` holds, for ``ne`` elements, the stress resultant - strain relation of a
PSHELL in the MATERIAL axes (Nastran QRG, PSHELL remarks; MSC Nastran Reference Manual, "Shell
elements")::

    N = A eps + B kappa          eps   = [eps_x, eps_y, gamma_xy]          (engineering shear)
    M = B eps + D kappa          kappa = [kappa_x, kappa_y, 2 kappa_xy]
    Q = S gamma                  gamma = [gamma_xz, gamma_yz]

for strains eps(z) = eps + z kappa through the thickness (z along the element normal; kappa_x =
-w,xx for a Kirchhoff plate), with ``A = T G1``, ``B = T^2 G4``,
``D = (12 I / T^3) (T^3 / 12) G2`` and ``S = (TS/T) T G3``, where ``Gi`` is the material matrix of
MIDi (PSHELL fields MID1..MID4, 12I/T**3 and TS/T). A blank MID2 gives a membrane-only shell
(``D = 0``, ``S = 0``); a blank MID3 with MID2 present means "no transverse shear flexibility"
(Kirchhoff plate), flagged in ``shear_rigid`` so that the element can impose it. Z1/Z2 only locate
stress recovery fibres and do not enter the stiffness.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from structures.common.errors import InputError, MissingReferenceError, card_message


def _check_finite(card: str, mid: int, **values: float) -> None:
    for name, value in values.items():
        if not np.isfinite(value):
            raise InputError(card_message(f"field {name} is not a finite number ({value}).",
                                          card=card, card_id=mid, fix=f"give {card} {name} a real value."))


@dataclass(frozen=True)
class Mat1:
    """Isotropic material (Nastran MAT1) after Nastran's blank-field rule.

    Build it with :meth:`from_fields` when some of E, G, NU may be blank: Nastran completes the missing
    one from ``E = 2 (1 + NU) G`` (QRG MAT1, remark 3); if two are blank they are both zero.
    """

    mid: int
    e: float
    g: float
    nu: float
    rho: float = 0.0

    def __post_init__(self) -> None:
        _check_finite("MAT1", self.mid, E=self.e, G=self.g, NU=self.nu, RHO=self.rho)
        if self.e < 0 or self.g < 0 or self.rho < 0:
            raise InputError(card_message("E, G and RHO must not be negative.", card="MAT1",
                                          card_id=self.mid, fix="correct the sign of the modulus/density."))

    @classmethod
    def from_fields(cls, mid: int, e: float | None, g: float | None, nu: float | None,
                    rho: float | None = 0.0) -> "Mat1":
        """Complete blank E, G or NU as Nastran does (QRG MAT1 remark 3)."""
        blanks = [v is None for v in (e, g, nu)]
        if all(blanks):
            raise InputError(card_message("E, G and NU are all blank.", card="MAT1", card_id=mid,
                                          fix="give at least E or G."))
        if sum(blanks) == 2:  # QRG: the two blank ones become 0.0
            e, g, nu = (e or 0.0), (g or 0.0), (nu or 0.0)
        elif e is None:
            e = 2.0 * (1.0 + nu) * g                       # E = 2 (1 + nu) G
        elif g is None:
            g = e / (2.0 * (1.0 + nu))                     # G = E / (2 (1 + nu))
        elif nu is None:
            nu = e / (2.0 * g) - 1.0 if g > 0 else 0.0     # nu = E / (2 G) - 1
        return cls(mid, float(e), float(g), float(nu), float(rho or 0.0))

    def plane_stress(self) -> np.ndarray:
        """Plane-stress matrix Q (3, 3) for [eps_x, eps_y, gamma_xy].

        The shear term is G (so that MAT1 with independent E, G, NU behaves as Nastran's MAT1).
        """
        c = self.e / (1.0 - self.nu ** 2)  # Timoshenko & Woinowsky-Krieger, plane stress
        return np.array([[c, c * self.nu, 0.0], [c * self.nu, c, 0.0], [0.0, 0.0, self.g]])

    def transverse_shear(self) -> np.ndarray:
        """Transverse shear matrix (2, 2) for [gamma_xz, gamma_yz] when used as MID3."""
        return self.g * np.eye(2)


@dataclass(frozen=True)
class Mat2:
    """Anisotropic plane-stress material (Nastran MAT2): the symmetric matrix G11..G33.

    As MID3, QRG MAT2 remark: G11, G12, G22 form the 2x2 transverse shear matrix.
    """

    mid: int
    g11: float
    g12: float
    g13: float
    g22: float
    g23: float
    g33: float
    rho: float = 0.0

    def __post_init__(self) -> None:
        _check_finite("MAT2", self.mid, G11=self.g11, G12=self.g12, G13=self.g13, G22=self.g22,
                      G23=self.g23, G33=self.g33, RHO=self.rho)

    def plane_stress(self) -> np.ndarray:
        """The matrix (3, 3) [[G11, G12, G13], [G12, G22, G23], [G13, G23, G33]]."""
        return np.array([[self.g11, self.g12, self.g13], [self.g12, self.g22, self.g23],
                         [self.g13, self.g23, self.g33]], dtype=float)

    def transverse_shear(self) -> np.ndarray:
        """[[G11, G12], [G12, G22]] (QRG MAT2: the MID3 use of the card)."""
        return np.array([[self.g11, self.g12], [self.g12, self.g22]], dtype=float)


@dataclass(frozen=True)
class Mat8:
    """Orthotropic plane-stress material (Nastran MAT8).

    ``g1z``/``g2z`` None means a blank field: infinitely stiff in transverse shear.
    """

    mid: int
    e1: float
    e2: float
    nu12: float
    g12: float
    g1z: float | None = None
    g2z: float | None = None
    rho: float = 0.0

    def __post_init__(self) -> None:
        _check_finite("MAT8", self.mid, E1=self.e1, E2=self.e2, NU12=self.nu12, G12=self.g12,
                      RHO=self.rho)
        if self.e1 <= 0 or self.e2 <= 0:
            raise InputError(card_message("E1 and E2 must be positive.", card="MAT8",
                                          card_id=self.mid, fix="give positive E1 and E2."))

    def plane_stress(self) -> np.ndarray:
        """Orthotropic plane-stress Q (3, 3) (Jones, Mechanics of Composite Materials, eq. 2.61)."""
        nu21 = self.nu12 * self.e2 / self.e1              # reciprocity nu21 = nu12 E2 / E1
        den = 1.0 - self.nu12 * nu21
        q11, q22, q12 = self.e1 / den, self.e2 / den, self.nu12 * self.e2 / den
        return np.array([[q11, q12, 0.0], [q12, q22, 0.0], [0.0, 0.0, self.g12]])

    def transverse_shear(self) -> np.ndarray | None:
        """diag(G1Z, G2Z), or None when a field is blank (rigid in transverse shear)."""
        if self.g1z is None or self.g2z is None:
            return None
        return np.diag([float(self.g1z), float(self.g2z)])


Material = Mat1 | Mat2 | Mat8


@dataclass(frozen=True)
class PShell:
    """Nastran PSHELL fields that enter stiffness and mass (None = blank field)."""

    pid: int
    t: float
    mid1: int | None = None
    mid2: int | None = None
    bending_ratio: float = 1.0           # 12I/T**3
    mid3: int | None = None
    shear_ratio: float = 5.0 / 6.0       # TS/T (QRG default 0.833333)
    nsm: float = 0.0
    mid4: int | None = None

    def __post_init__(self) -> None:
        if not (np.isfinite(self.t) and self.t > 0):
            raise InputError(card_message(f"thickness T = {self.t} must be positive.", card="PSHELL",
                                          card_id=self.pid, fix="give T > 0 (element Ti are not supported)."))
        if self.mid1 is None and self.mid2 is None:
            raise InputError(card_message("MID1 and MID2 are both blank.", card="PSHELL",
                                          card_id=self.pid, fix="give MID1 (membrane) and/or MID2 (bending)."))
        if self.mid2 is not None and self.mid2 < 0:
            raise InputError(card_message("MID2 = -1 (plane strain) is not supported.", card="PSHELL",
                                          card_id=self.pid, fix="use a positive MID2 or leave it blank."))
        if self.mid4 is not None and (self.mid1 is None or self.mid2 is None):
            raise InputError(card_message("MID4 requires both MID1 and MID2.", card="PSHELL",
                                          card_id=self.pid, fix="blank MID4 or give MID1 and MID2."))


@dataclass(frozen=True)
class ShellSection:
    """Stacked section stiffness of ``ne`` shell elements, in the MATERIAL axes.

    Attributes
    ----------
    A, B, D : ndarray (ne, 3, 3)
        Membrane [force/length], coupling [force] and bending [force*length] stiffness.
    S : ndarray (ne, 2, 2)
        Transverse shear stiffness [force/length].
    mass_per_area : ndarray (ne,)
        rho*T + NSM [mass/area].
    shear_rigid : ndarray (ne,) bool
        True where MID3 is blank but MID2 is not: no transverse shear flexibility (Kirchhoff).
    """

    A: np.ndarray
    B: np.ndarray
    D: np.ndarray
    S: np.ndarray
    mass_per_area: np.ndarray
    shear_rigid: np.ndarray

    def __post_init__(self) -> None:
        ne = np.shape(self.mass_per_area)[0] if np.ndim(self.mass_per_area) == 1 else -1
        shapes = {"A": (ne, 3, 3), "B": (ne, 3, 3), "D": (ne, 3, 3), "S": (ne, 2, 2),
                  "shear_rigid": (ne,)}
        for name, shape in shapes.items():
            value = np.asarray(getattr(self, name))
            if ne < 0 or value.shape != shape:
                raise InputError(f"ShellSection.{name} has shape {value.shape}, expected {shape} "
                                 "(mass_per_area must be 1-D with ne entries). Fix: stack per-element "
                                 "sections with stack_sections().")
        for name in ("A", "B", "D", "S", "mass_per_area"):
            arr = np.array(getattr(self, name), dtype=float)  # private read-only copy
            if not np.all(np.isfinite(arr)):
                raise InputError(f"ShellSection.{name} contains non-finite values. Fix: check the "
                                 "PSHELL/MAT cards.")
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)
        rigid = np.array(self.shear_rigid, dtype=bool)
        rigid.flags.writeable = False
        object.__setattr__(self, "shear_rigid", rigid)

    @property
    def ne(self) -> int:
        """Number of elements."""
        return int(self.mass_per_area.shape[0])

    def take(self, index: np.ndarray) -> "ShellSection":
        """The sections of the elements ``index`` (any numpy index)."""
        return ShellSection(self.A[index], self.B[index], self.D[index], self.S[index],
                            self.mass_per_area[index], self.shear_rigid[index])


def stack_sections(sections: list[ShellSection]) -> ShellSection:
    """Concatenate sections along the element axis."""
    if not sections:
        raise InputError("stack_sections got an empty list. Fix: pass at least one ShellSection.")
    return ShellSection(*(np.concatenate([getattr(s, f) for s in sections]) for f in
                          ("A", "B", "D", "S", "mass_per_area", "shear_rigid")))


def material_from_fields(mid: int, card: str, fields: Mapping[str, float | None]) -> Material:
    """Build a Mat1/Mat2/Mat8 from a card name and its fields keyed by Nastran field names.

    MAT1: ``E``, ``G``, ``NU``, ``RHO``; MAT2: ``G11``..``G33``, ``RHO``; MAT8: ``E1``, ``E2``,
    ``NU12``, ``G12``, ``G1Z``, ``G2Z``, ``RHO``. Missing keys are blank fields.
    """
    get = lambda key, default=None: default if fields.get(key) is None else float(fields[key])  # noqa: E731
    if card == "MAT1":
        return Mat1.from_fields(mid, get("E"), get("G"), get("NU"), get("RHO", 0.0))
    if card == "MAT2":
        return Mat2(mid, *(get(k, 0.0) for k in ("G11", "G12", "G13", "G22", "G23", "G33")),
                    rho=get("RHO", 0.0))
    if card == "MAT8":
        return Mat8(mid, get("E1"), get("E2"), get("NU12", 0.0), get("G12", 0.0), get("G1Z"),
                    get("G2Z"), get("RHO", 0.0))
    raise InputError(card_message(f"{card} cannot be used by a PSHELL.", card=card, card_id=mid,
                                  fix="use MAT1, MAT2 or MAT8."))


def pshell_from_fields(pid: int, fields: Mapping[str, float | None]) -> PShell:
    """Build a PShell from fields keyed by Nastran names: ``T``, ``MID1``, ``MID2``, ``12I/T**3``,
    ``MID3``, ``TS/T``, ``NSM``, ``MID4`` (``Z1``/``Z2`` ignored; missing or None = blank;
    a material id of 0 counts as blank, as pyNastran stores some blanks)."""
    def mid(key: str) -> int | None:
        value = fields.get(key)
        return None if value is None or int(value) == 0 else int(value)
    get = lambda key, default: default if fields.get(key) is None else float(fields[key])  # noqa: E731
    return PShell(pid, get("T", float("nan")), mid("MID1"), mid("MID2"), get("12I/T**3", 1.0),
                  mid("MID3"), get("TS/T", 5.0 / 6.0), get("NSM", 0.0), mid("MID4"))


def _material(materials: dict[int, Material], mid: int, pid: int, field: str) -> Material:
    try:
        return materials[mid]
    except KeyError:
        raise MissingReferenceError(card_message(
            f"{field} = {mid} refers to a material that is not defined (MAT1/MAT2/MAT8).",
            card="PSHELL", card_id=pid, fix=f"add material {mid} or correct {field}.")) from None


def pshell_section(pshell: PShell, materials: dict[int, Material], ne: int = 1) -> ShellSection:
    """Section stiffness of one PSHELL, repeated for ``ne`` elements.

    Parameters
    ----------
    pshell : PShell
    materials : dict int -> Mat1 | Mat2 | Mat8
        Materials by id.
    ne : int
        How many copies (elements) to return.

    Returns
    -------
    ShellSection with arrays of leading dimension ``ne``.
    """
    t = pshell.t
    zero3 = np.zeros((3, 3))
    A = B = D = zero3
    S = np.zeros((2, 2))
    rho_t = 0.0
    rigid = False
    if pshell.mid1 is not None:
        m1 = _material(materials, pshell.mid1, pshell.pid, "MID1")
        A = t * m1.plane_stress()                                   # A = T G1 (QRG PSHELL)
        rho_t = m1.rho * t
    if pshell.mid2 is not None:
        m2 = _material(materials, pshell.mid2, pshell.pid, "MID2")
        D = pshell.bending_ratio * t ** 3 / 12.0 * m2.plane_stress()  # D = (12I/T^3) T^3/12 G2
        if pshell.mid1 is None:
            rho_t = m2.rho * t
        if pshell.mid3 is None:
            rigid = True                                            # QRG: no shear flexibility
        else:
            g3 = _material(materials, pshell.mid3, pshell.pid, "MID3").transverse_shear()
            if g3 is None:
                rigid = True
            else:
                S = pshell.shear_ratio * t * g3                     # S = (TS/T) T G3
    if pshell.mid4 is not None:
        m4 = _material(materials, pshell.mid4, pshell.pid, "MID4")
        B = t ** 2 * m4.plane_stress()                              # B = T^2 G4
    stacked = [np.repeat(np.asarray(a, float)[None], ne, axis=0) for a in (A, B, D, S)]
    return ShellSection(*stacked, np.full(ne, rho_t + pshell.nsm), np.full(ne, rigid))
