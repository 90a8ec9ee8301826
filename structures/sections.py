"""Beam-library cross-sections (PBARL / PBEAML TYPE + DIMi) as equivalent PBAR / PBEAM properties.

Nastran derives an internal PBAR/PBEAM from the TYPE and the dimensions DIMi of a PBARL/PBEAML
(MSC QRG PBARL/PBEAML, remark "A function of this entry is to derive an equivalent internal PBAR
entry"). Area and the bending moments of inertia come from pyNastran's section functions
(``pyNastran.bdf.cards.properties.bars``, the DIMi conventions of the QRG figures); pyNastran gives
no torsion constant for PBEAML, and its ``PBARL.J()`` is the polar moment I1 + I2 (not the torsion
constant) for every non-circular section, so :func:`torsion_constant` supplies Saint-Venant's J:

* ROD (DIM1 = r): J = pi r^4 / 2; TUBE (DIM1 = r_o, DIM2 = r_i): J = pi (r_o^4 - r_i^4) / 2.
* BAR (DIM1 x DIM2, a >= b the longer and shorter side): J = a b^3 [1/3 - 0.21 (b/a)
  (1 - b^4 / (12 a^4))] (Roark's Formulas for Stress and Strain, 7th ed., Table 10.7 case 4).
* BOX (width DIM1, height DIM2, wall DIM3 top/bottom, DIM4 sides): Bredt's thin-walled closed
  section J = 4 A_m^2 / (sum of s / t) on the wall mid-lines (Roark, Table 10.7 case 16).
* L (legs DIM1, DIM2, thicknesses DIM3, DIM4): thin open section J = sum of s t^3 / 3 over the
  two legs (Roark, Table 10.7 case 26), the legs' overlap counted once.

A tapered PBEAML (several stations) is reduced like pyNastran's ``PBEAML.Area()``: each property
is integrated over the stations X/XB and the element uses the mean (the beam elements here are
prismatic). Transverse shear flexibility is not derived (K1 = K2 blank: Euler-Bernoulli).
"""
from __future__ import annotations

import numpy as np

from structures.common.errors import InputError, UnsupportedCardError, card_message

#: Section TYPEs whose A, I1, I2, I12 pyNastran computes and whose J is derived here (PBARL and
#: PBEAML alike).
SECTION_TYPES = ("ROD", "TUBE", "BAR", "BOX", "L")


def torsion_constant(beam_type: str, dim) -> float:
    """Saint-Venant torsion constant J of one beam-library section (see the module docstring).

    Parameters
    ----------
    beam_type : one of :data:`SECTION_TYPES`
    dim : sequence of float, the section's DIMi

    Returns
    -------
    float J [length^4]
    """
    d = [float(x) for x in dim]
    if beam_type == "ROD":
        return np.pi * d[0] ** 4 / 2.0
    if beam_type == "TUBE":
        return np.pi * (d[0] ** 4 - d[1] ** 4) / 2.0
    if beam_type == "BAR":
        a, b = max(d[0], d[1]), min(d[0], d[1])
        return a * b ** 3 * (1.0 / 3.0 - 0.21 * (b / a) * (1.0 - b ** 4 / (12.0 * a ** 4)))
    if beam_type == "BOX":
        width, height, t_flange, t_web = d[:4]
        bm, hm = width - t_web, height - t_flange                    # wall mid-lines
        return 4.0 * (bm * hm) ** 2 / (2.0 * bm / t_flange + 2.0 * hm / t_web)
    if beam_type == "L":
        leg1, leg2, t1, t2 = d[:4]
        return (leg1 * t1 ** 3 + (leg2 - t1) * t2 ** 3) / 3.0
    raise ValueError(f"no torsion constant for section TYPE {beam_type!r}; known: {SECTION_TYPES}")


def section_fields(card: str, pid: int, mid: int, beam_type: str, stations, xxb, nsm,
                   filename: str | None = None) -> dict:
    """Equivalent PBAR / PBEAM fields (MID, A, I1, I2, I12, J, NSM, K1, K2) of a PBARL / PBEAML.

    Parameters
    ----------
    card : "PBARL" or "PBEAML" (for messages)
    pid, mid : the card's PID and MID
    beam_type : the card's TYPE
    stations : sequence (nstation,) of DIMi sequences (one station for a PBARL)
    xxb : (nstation,) station positions X/XB, 0 to 1
    nsm : (nstation,) non-structural mass per length at each station
    filename : deck name for error messages

    Returns
    -------
    dict of field name -> value (K1, K2 None: no transverse shear flexibility)
    """
    from pyNastran.bdf.cards.properties import bars
    from pyNastran.utils.mathematics import integrate_positive_unit_line, integrate_unit_line

    if beam_type not in SECTION_TYPES:
        raise UnsupportedCardError(card_message(
            f"section TYPE {beam_type} is not supported.", card=card, card_id=pid,
            filename=filename, fix=f"use a TYPE among {', '.join(SECTION_TYPES)} or give the "
            f"section properties on a {card[:-1]}."))
    section = {"ROD": bars.rod_section, "TUBE": bars.tube_section, "BAR": bars.bar_section,
               "BOX": bars.box_section, "L": bars.l_section}[beam_type]
    try:
        per_station = np.array([list(section(card, beam_type, np.asarray(dim, float), None))
                                + [torsion_constant(beam_type, dim)] for dim in stations])
    except AssertionError:  # pyNastran's section functions check their DIMi with assert
        raise InputError(card_message(
            f"the {beam_type} section dimensions {[list(map(float, d)) for d in stations]} do "
            "not describe a section (e.g. walls thicker than half the box, inner radius above "
            "the outer).", card=card, card_id=pid, filename=filename,
            fix="correct the DIMi fields (MSC QRG PBARL/PBEAML figures).")) from None
    x = [float(v) for v in xxb]
    if len(x) == 1:
        a, i1, i2, i12, j = per_station[0]
        mass = float(nsm[0])
    else:
        a, i1, i2, j = (integrate_positive_unit_line(x, per_station[:, k].tolist())
                        for k in (0, 1, 2, 4))
        i12 = integrate_unit_line(x, per_station[:, 3].tolist())
        mass = integrate_positive_unit_line(x, [float(v) for v in nsm])
    return dict(MID=mid, A=float(a), I1=float(i1), I2=float(i2), I12=float(i12), J=float(j),
                NSM=float(mass), K1=None, K2=None)
