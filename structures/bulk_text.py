"""Small-field (8-character) Nastran bulk-data text, for decks the project writes itself.

Generated decks (benchmarks, validation and MYSTRAN cross-check decks) use these so that both
pyNastran and MYSTRAN read them; MYSTRAN requires a decimal point in every real.
"""
from __future__ import annotations

import numpy as np

from structures.common.errors import InputError


def real8(value: float) -> str:
    """A real in at most 8 characters with a decimal point (``2.5E-3`` form when needed)."""
    for digits in range(8, 0, -1):
        text = f"{float(value):.{digits}g}"
        if "e" in text:
            mantissa, exponent = text.split("e")
            text = mantissa + ("" if "." in mantissa else ".") + f"E{int(exponent)}"
        elif "." not in text:
            text += "."
        if len(text) <= 8:
            return text
    raise InputError(f"{value!r} does not fit an 8-character field. Fix: use large-field format.")


def field(value) -> str:
    """One 8-character small-field entry: blank for None, integers, strings or reals."""
    if value is None:
        return " " * 8
    if isinstance(value, (int, np.integer)):
        text = str(int(value))
    elif isinstance(value, str):
        text = value
    else:
        text = real8(value)
    if len(text) > 8:
        raise InputError(f"{value!r} does not fit an 8-character field. Fix: shorten it.")
    return f"{text:<8s}"


def card(*values) -> str:
    """A card from its fields; continuation lines every 8 data fields."""
    head, data = values[0], list(values[1:])
    lines = [field(head) + "".join(field(v) for v in data[:8])]
    data = data[8:]
    while data:
        lines.append(" " * 8 + "".join(field(v) for v in data[:8]))
        data = data[8:]
    return "\n".join(line.rstrip() for line in lines)
