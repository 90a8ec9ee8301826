"""The one Nastran deck reader: file-level checks, then pyNastran.

Every part that needs bulk-data cards (structures, aero, flutter) reads a deck through
:func:`read_pynastran`, so a bad file fails the same way everywhere: missing, empty, binary (an OP2
given as a deck), a missing or circular INCLUDE, an absurd THRU range, or any card pyNastran cannot
parse is an :class:`~structures.common.errors.InputError` naming the file, the line and the fix.
"""
from __future__ import annotations

import io
import logging
import re
from contextlib import redirect_stdout
from pathlib import Path

from structures.common.errors import InputError, card_message

#: An OP2 file starts with a Fortran record marker (4) and holds NUL bytes near its start.
_OP2_MARKER = b"\x04\x00\x00\x00"
_BINARY_PROBE = 4096


def _deck_text(path: Path) -> str:
    """The deck's text after the file-level checks: exists, is a file, not empty, not binary."""
    filename = str(path)
    if not path.exists():
        raise InputError(card_message("no such deck.", filename=filename,
                                      fix="check the path (relative to the current folder)."))
    if not path.is_file():
        raise InputError(card_message("is a folder, not a deck.", filename=filename,
                                      fix="give the .bdf/.dat file inside it."))
    raw = path.read_bytes()
    if not raw.strip():
        raise InputError(card_message("the deck is empty.", filename=filename,
                                      fix="give a bulk-data deck with GRID and element cards."))
    if raw[:4] == _OP2_MARKER or b"\x00" in raw[:_BINARY_PROBE]:
        raise InputError(card_message(
            "is a binary file (an OP2 result file?), not a bulk-data deck.", filename=filename,
            fix="give the text input deck (.bdf/.dat); modes computed by Nastran are imported "
                "from the OP2 with structures.nastran_results."))
    return raw.decode("latin-1")


def _check_includes(path: Path, text: str, include_dir: str, chain: tuple = ()) -> list[Path]:
    """The files ``path`` includes, directly or not, after checking them.

    Every INCLUDE of ``path`` (and of the files it includes) names an existing file, no file
    includes itself, and no THRU range is absurd (:func:`_check_thru_ranges`). pyNastran would
    otherwise dump ``pyNastran_crash.bdf`` into the current folder (or recurse without end, or
    expand 1e8 ids) before failing; its own INCLUDE resolution rule is used
    (:func:`pyNastran.bdf.bdf_interface.include_file.get_include_filename`, relative to the main
    deck's folder)."""
    from pyNastran.bdf.bdf_interface.include_file import get_include_filename

    _check_thru_ranges(path, text)
    if "INCLUDE" not in text.upper():
        return []
    chain = chain + (path.resolve(),)
    lines = text.splitlines()
    included = []
    i = 0
    while i < len(lines):
        if not lines[i].lstrip().upper().startswith("INCLUDE"):
            i += 1
            continue
        first, card = i + 1, [lines[i].split("$")[0]]
        while "".join(card).count("'") == 1 and i + 1 < len(lines):
            i += 1
            card.append(lines[i].split("$")[0])
        i += 1
        try:
            target = Path(get_include_filename(card, include_dir=include_dir))
        except Exception as exc:  # pyNastran's parse of the statement: any failure is the deck's
            raise InputError(card_message(
                f"line {first}: cannot read the INCLUDE statement {' '.join(card).strip()!r} "
                f"({exc}).", filename=str(path), fix="write INCLUDE 'file name' with the name in "
                "single quotes.")) from None
        try:
            exists = target.is_file()
        except OSError:  # e.g. a name that swallowed the following lines: too long for the system
            exists = False
        if not exists:
            shown = target.name if len(target.name) <= 80 else target.name[:80] + "..."
            raise InputError(card_message(
                f"line {first}: INCLUDE names {shown!r}, which does not exist (looked for "
                f"{target.parent / shown}).", filename=str(path), fix="copy the included file there or correct "
                "the name (relative names are relative to the main deck's folder)."))
        if target.resolve() in chain:
            raise InputError(card_message(
                f"line {first}: INCLUDE {target.name!r} includes a file that is already being "
                f"read ({' -> '.join(p.name for p in chain)} -> {target.name}).",
                filename=str(path), fix="remove the circular INCLUDE."))
        included += [target, *_check_includes(target, _deck_text(target), include_dir, chain)]
    return included


def deck_files(path) -> list[Path]:
    """The deck and every file it INCLUDEs (checked as :func:`read_pynastran` checks them): the
    files whose content a result computed from the deck depends on."""
    path = Path(path)
    if not path.is_file():
        raise InputError(card_message("no such deck.", filename=str(path),
                                      fix="check the path."))
    return [path, *_check_includes(path, _deck_text(path), str(path.resolve().parent))]


#: Largest id range of a "THRU" list (SET1, SPC1, ...) read: pyNastran expands the range into a list
#: (1e6 ids take 0.3 s; 1e8 did not finish in 200 s and took over 5 GB).
MAX_THRU_RANGE = 10_000_000
_THRU = re.compile(r"([+-]?\d+)[,\s]*THRU[,\s]*([+-]?\d+)", re.IGNORECASE)


def _check_thru_ranges(path: Path, text: str) -> None:
    """Refuse id ranges ``a THRU b`` longer than :data:`MAX_THRU_RANGE` before pyNastran expands
    them."""
    if not _THRU.search(text):
        return
    for number, line in enumerate(text.splitlines(), 1):
        for match in _THRU.finditer(line.split("$")[0]):
            low, high = int(match.group(1)), int(match.group(2))
            if high - low > MAX_THRU_RANGE:
                raise InputError(card_message(
                    f"line {number}: the id range {low} THRU {high} spans {high - low + 1:,} ids "
                    f"(at most {MAX_THRU_RANGE:,} are read).", filename=str(path),
                    fix="list the ids that exist, or correct the range's end."))


def read_pynastran(path):
    """Parse a deck with pyNastran (INCLUDEs followed, grids cross-referenced): the one reader.

    Every part that needs bulk-data cards (structures, aero, flutter) reads the deck here, so a bad
    file fails the same way everywhere.

    Parameters
    ----------
    path : str or Path
        The deck; with or without executive and case control sections.

    Returns
    -------
    pyNastran.bdf.bdf.BDF

    Raises
    ------
    InputError
        Missing, empty or binary file, BEGIN BULK without CEND, or any card pyNastran cannot parse
        (the message carries pyNastran's own words, which name the card and line when it knows).
    """
    from pyNastran.bdf.bdf import BDF

    path = Path(path)
    text = _deck_text(path)
    _check_includes(path, text, str(path.resolve().parent))
    text = text.upper()
    # A file without an executive/case control section is bulk data only (a "punch" file).
    lines = [line.strip() for line in text.splitlines()]
    punch = not any(line.startswith("CEND") for line in lines)
    if punch and any(line.startswith("BEGIN") and "BULK" in line for line in lines):
        raise InputError(f"file {path}: BEGIN BULK without an executive/case control section "
                         "(no CEND). Fix: remove the BEGIN BULK line for a bulk-data-only file, or "
                         "add the executive and case control sections ending with CEND.")
    model = BDF(debug=None, log=logging.getLogger("pynastran.quiet"))
    logging.getLogger("pynastran.quiet").setLevel(logging.CRITICAL)
    try:
        with redirect_stdout(io.StringIO()):
            model.read_bdf(str(path), xref=False, validate=False, punch=punch)
            model.cross_reference(xref=True, xref_nodes=True, xref_elements=False,
                                  xref_properties=False, xref_masses=False, xref_materials=False,
                                  xref_loads=False, xref_constraints=False, xref_aero=False,
                                  xref_sets=False, xref_optimization=False)
    except Exception as exc:  # pyNastran signals bad decks with many exception types
        if isinstance(exc, InputError):
            raise
        try:
            with redirect_stdout(io.StringIO()):  # pyNastran prints while formatting some cards
                said = " ".join(str(exc).split())
        except ValueError:  # some pyNastran messages fail to format a card holding inf
            said = "(pyNastran's message could not be formatted)"
        said = said if len(said) <= 400 else said[:400] + " ..."
        raise InputError(card_message(
            f"pyNastran could not read the deck ({type(exc).__name__}: {said}).",
            filename=str(path), fix="correct the card and line named above (field formats, "
            "continuation lines, missing INCLUDE files, coordinate-system references).")) from exc
    return model
