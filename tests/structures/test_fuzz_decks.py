"""Fuzz test of the deck path (issue 10): mutated Nastran decks end in a result or a named error.

The seeds are the shared decks in ``tests/data`` (BAH jet transport with three INCLUDEs, the PT145
swept wing, the two-mode flutter plate with four INCLUDEs). Each example applies one to three
mutations -- a card dropped, duplicated or garbled (random printable characters in a field, a line
cut short), a field set to NaN / inf / a negated value / 0 / 1e300 / text / blank, fields shifted by
one, an INCLUDE target removed, a file that INCLUDEs itself -- and then runs ``read_model``,
``assemble`` and ``compute_modes(model, 6)``, separately ``read_aero_model``, and when both work
the generalized aerodynamic forces at the deck's first Mach-k pair. Each either returns or raises
a :class:`structures.common.errors.PipelineError` whose message names the deck or one of its
included files; warnings are allowed; any other exception fails the test. The default tests are
derandomized (the same examples on every run); the ``slow`` ones draw thousands at random.

Card boundaries are parsed properly: small-field (8-column), large-field (``*``, 16-column) and
free-field (comma) lines all appear in the seeds, and a card's continuation lines start with ``+``,
``*``, a comma or a blank name field.
"""
from __future__ import annotations

import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from aero.gaf import generalized_aero_forces
from aero.model import read_aero_model
from structures.assembly import assemble
from structures.bdf import read_model
from structures.common.errors import PipelineError
from structures.modal import compute_modes

DATA = Path(__file__).resolve().parents[1] / "data"

#: Seed decks: folder, main deck, INCLUDEd files.
SEEDS = {
    "bah_plane": ("bah_plane.bdf", ("structure_bah.inc", "aero_bah.inc", "interface_bah.inc")),
    "pt145": ("pt145.bdf", ()),
    "two_mode_flutter": ("0012_flutter.bdf", ("aero_cards.inc", "flutter_cards.inc",
                                              "rigid_modes.inc", "geom.inc")),
}
TEXTS = {folder: {name: (DATA / folder / name).read_text().splitlines()
                  for name in (main, *incs)} for folder, (main, incs) in SEEDS.items()}

#: Replacement values of one field, by the kind of the value it replaces (real, integer, other):
#: mostly values that still parse (NaN, inf, negated, zero, huge), sometimes the wrong type.
#: "99999999" in an integer field also makes absurd THRU ranges (SET1,1,1,THRU,99999999: pyNastran
#: would expand 1e8 ids; structures.bdf refuses them before it reads).
VALUES = {
    "real": ("NaN", "nan", "inf", "-inf", "0.", "1e300", "1.+300", "-1e300", "negate", "negate",
             "ABC", ""),
    "int": ("0", "-1", "negate", "negate", "1.5", "NaN", "", "99999999"),
    "other": ("ABC", "", "0", "1.", "NaN"),
}
PRINTABLE = st.characters(min_codepoint=32, max_codepoint=126)
#: The GAF step runs on meshes up to this size (the seeds have 24 to 228 boxes): a garbled NSPAN
#: of a few thousand is a legal deck whose AIC would need tens of GB (the reader stops at
#: aero.model.MAX_BOXES; the doublet lattice itself does not check memory).
GAF_MAX_BOXES = 1000
#: Mutation kinds, repeated to weight them: field values most often (they reach the project's
#: own checks; a missing or self-including file stops in pyNastran's INCLUDE handling).
KINDS = ("value",) * 6 + ("garble", "shift") * 2 + ("drop", "drop", "duplicate", "cut",
                                                      "self_include", "remove_include")


@dataclass(frozen=True)
class Card:
    """One bulk-data card: lines ``start`` to ``stop - 1`` of file ``name``."""

    name: str
    start: int
    stop: int


@dataclass(frozen=True)
class MutatedDeck:
    """A seed deck after mutations: file texts by name, files removed, what was done."""

    folder: str
    main: str
    files: dict
    removed: tuple
    log: tuple

    def __repr__(self) -> str:
        return f"MutatedDeck({self.folder}: {'; '.join(self.log)})"

    def _repr_pretty_(self, printer, cycle) -> None:  # hypothesis prints falsifying examples so
        printer.text(repr(self))

    def write(self, folder: Path) -> Path:
        for name, lines in self.files.items():
            if name not in self.removed:
                (folder / name).write_text("\n".join(lines) + "\n")
        return folder / self.main


def _body(line: str) -> str:
    """The line without its trailing ``$`` comment."""
    return line.split("$", 1)[0]


def _is_continuation(line: str) -> bool:
    return line[:1] in ("+", "*", ",", " ", "\t")


def cards(lines: list, main: bool) -> list:
    """Card boundaries of one file: the bulk section (after BEGIN BULK in the main deck) up to
    ENDDATA; comments and blank lines are skipped, continuation lines belong to their card.
    Returns a list of ``(start, stop)`` line ranges."""
    start = 0
    if main:
        start = next((i + 1 for i, line in enumerate(lines)
                      if line.strip().upper().startswith("BEGIN") and "BULK" in line.upper()),
                     len(lines))
    out = []
    for i in range(start, len(lines)):
        line = lines[i]
        if not _body(line).strip():
            continue
        if _is_continuation(line) and out:
            out[-1][1] = i + 1
            continue
        out.append([i, i + 1])
        if line.strip().upper().startswith("ENDDATA"):
            break
    return [tuple(c) for c in out]


def _layout(line: str) -> str:
    body = _body(line)
    if "," in body:
        return "free"
    return "large" if body[:8].strip().endswith("*") or body[:1] == "*" else "small"


def nfields(line: str) -> int:
    """Number of data fields (name and continuation fields excluded) of one line."""
    kind = _layout(line)
    if kind == "free":
        return max(len(_body(line).split(",")) - 1, 1)
    return 4 if kind == "large" else 8


def _fixed(line: str) -> tuple:
    width = 16 if _layout(line) == "large" else 8
    return _body(line).expandtabs(8).ljust(8 + 8 * 8), width


def get_field(line: str, i: int) -> str:
    """Data field ``i`` (1-based) of a line."""
    if _layout(line) == "free":
        parts = _body(line).split(",")
        return parts[i].strip() if i < len(parts) else ""
    text, width = _fixed(line)
    return text[8 + width * (i - 1):8 + width * i].strip()


def set_field(line: str, i: int, value: str) -> str:
    """The line with data field ``i`` (1-based) replaced by ``value`` (cut to the field width)."""
    if _layout(line) == "free":
        parts = _body(line).split(",")
        parts += [""] * (i + 1 - len(parts))
        parts[i] = value
        return ",".join(parts)
    text, width = _fixed(line)
    a = 8 + width * (i - 1)
    return (text[:a] + value[:width].ljust(width) + text[a + width:]).rstrip()


def shift_fields(line: str, i: int, insert: bool) -> str:
    """The line with an empty field inserted before data field ``i`` (later fields move right),
    or with field ``i`` deleted (later fields move left)."""
    if _layout(line) == "free":
        parts = _body(line).split(",")
        parts += [""] * (i + 1 - len(parts))
        if insert:
            parts.insert(i, "")
        else:
            del parts[i]
        return ",".join(parts)
    text, width = _fixed(line)
    a = 8 + width * (i - 1)
    return (text[:a] + " " * width + text[a:] if insert else text[:a] + text[a + width:]).rstrip()


def _kind_of(text: str) -> str:
    """'int', 'real' or 'other': the kind of value a field holds."""
    body = text.strip().lstrip("+-")
    if body.isdigit():
        return "int"
    return "real" if body[:1].isdigit() or body[:2].replace(".", "0").isdigit() else "other"


def _negate(text: str) -> str:
    text = text.strip()
    return text[1:] if text.startswith("-") else "-" + (text or "1.")


def _real_fields(folder: str) -> list:
    """(file, line, field) of every field of the seed that holds a real number."""
    main, _ = SEEDS[folder]
    out = []
    for name, lines in TEXTS[folder].items():
        for start, stop in cards(lines, name == main):
            out += [(name, row, i) for row in range(start, stop)
                    for i in range(1, nfields(lines[row]) + 1)
                    if _kind_of(get_field(lines[row], i)) == "real"]
    return out


REAL_FIELDS = {folder: _real_fields(folder) for folder in SEEDS}
#: Values that still parse as reals: they pass pyNastran and reach the project's own checks.
BAD_REALS = ("NaN", "inf", "-inf", "0.", "1e300", "-1e300", "negate")


@st.composite
def bad_real_values(draw) -> MutatedDeck:
    """A seed deck with one real-valued field set to NaN, +-inf, 0, +-1e300 or its negative."""
    folder = draw(st.sampled_from(sorted(SEEDS)))
    files = {name: list(lines) for name, lines in TEXTS[folder].items()}
    name, row, i = draw(st.sampled_from(REAL_FIELDS[folder]))
    old = get_field(files[name][row], i)
    value = draw(st.sampled_from(BAD_REALS))
    value = _negate(old) if value == "negate" else value
    files[name][row] = set_field(files[name][row], i, value)
    card = _body(files[name][row]).replace(",", " ").split()[0]
    return MutatedDeck(folder, SEEDS[folder][0], files, (),
                       (f"value {name}:{row + 1} {card} field {i} {old!r} -> {value!r}",))


@st.composite
def mutated_decks(draw, kinds=KINDS, counts=(1, 1, 1, 2, 3)) -> MutatedDeck:
    """A seed deck with mutations of the given kinds, as many as one of ``counts`` (see the module
    docstring)."""
    folder = draw(st.sampled_from(sorted(SEEDS)))
    main, includes = SEEDS[folder]
    files = {name: list(lines) for name, lines in TEXTS[folder].items()}
    removed, log = [], []
    for _ in range(draw(st.sampled_from(counts))):
        kind = draw(st.sampled_from([k for k in kinds if includes or k != "remove_include"]))
        if kind == "remove_include":
            name = draw(st.sampled_from(includes))
            removed.append(name)
            log.append(f"remove {name}")
            continue
        name = draw(st.sampled_from(sorted(files)))
        lines = files[name]
        spans = cards(lines, name == main)
        if not spans:
            continue
        start, stop = draw(st.sampled_from(spans))
        card = _body(lines[start]).replace(",", " ").split()
        label = f"{name}:{start + 1} {card[0] if card else ''}"
        if kind == "drop":
            del lines[start:stop]
            log.append(f"drop {label}")
        elif kind == "duplicate":
            lines[stop:stop] = lines[start:stop]
            log.append(f"duplicate {label}")
        elif kind == "self_include":
            lines.insert(start, f"INCLUDE '{name}'")
            log.append(f"{name} includes itself at line {start + 1}")
        elif kind == "cut":
            row = draw(st.integers(start, stop - 1))
            col = draw(st.integers(0, max(len(lines[row]) - 1, 0)))
            lines[row] = lines[row][:col]
            log.append(f"cut {label} line {row + 1} at column {col}")
        else:
            row = draw(st.integers(start, stop - 1))
            i = draw(st.integers(1, nfields(lines[row])))
            old = get_field(lines[row], i)
            if kind == "garble":
                value = draw(st.text(PRINTABLE, min_size=1, max_size=8))
                lines[row] = set_field(lines[row], i, value)
            elif kind == "value":
                value = draw(st.sampled_from(VALUES[_kind_of(old)]))
                value = _negate(old) if value == "negate" else value
                lines[row] = set_field(lines[row], i, value)
            else:
                value = draw(st.sampled_from(("insert", "delete")))
                lines[row] = shift_fields(lines[row], i, value == "insert")
            log.append(f"{kind} {label} line {row + 1} field {i} {old!r} -> {value!r}")
    return MutatedDeck(folder, main, files, tuple(removed), tuple(log))


def _result_or_named_error(run, names):
    """Run and return its result, or None after a PipelineError, which must name one of the
    files; any other exception propagates."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return run()
    except PipelineError as exc:
        message = str(exc)
        assert any(name in message for name in names), f"no file named in: {message}"
    return None


def _modes(path: Path):
    model = read_model(path)
    return compute_modes(model, 6, system=assemble(model))


def check_deck(deck: MutatedDeck) -> None:
    """The property: the structural path (read, assemble, 6 modes), the aerodynamic reader and,
    when both give a result, the generalized aerodynamic forces at the deck's first MKAERO Mach-k
    pair (splines and doublet lattice; meshes up to GAF_MAX_BOXES) each end in a result or a PipelineError naming the deck
    or one of its included files."""
    names = tuple(deck.files)
    with tempfile.TemporaryDirectory() as tmp:
        path = deck.write(Path(tmp))
        modes = _result_or_named_error(lambda: _modes(path), names)
        aero = _result_or_named_error(lambda: read_aero_model(path), names)
        if modes is not None and aero is not None and len(aero.mach_k) and \
                len(aero.mesh) <= GAF_MAX_BOXES:
            mach, k = aero.mach_k[0]
            _result_or_named_error(lambda: generalized_aero_forces(aero, modes, [mach], [k]),
                                   names)


@pytest.mark.parametrize("folder", sorted(SEEDS))
def test_card_boundaries_match_pynastran(folder):
    """The card parser finds as many cards in the seeds as pyNastran reads (INCLUDE, ENDDATA and
    pyNastran-internal cards aside), so a dropped card removes all its continuation lines."""
    from pyNastran.bdf.bdf import BDF

    main, _ = SEEDS[folder]
    ours = 0
    for name, lines in TEXTS[folder].items():
        for start, _stop in cards(lines, name == main):
            word = _body(lines[start]).replace(",", " ").split()[0].upper()
            ours += word not in ("INCLUDE", "ENDDATA")
    bdf = BDF(debug=None)
    bdf.read_bdf(str(DATA / folder / main), xref=False, validate=False)
    theirs = sum(n for card, n in bdf.card_count.items() if card not in ("ENDDATA",))
    assert ours == theirs


@pytest.mark.parametrize("line, fields", [
    ("GRID,1,0,0.,2.286,0.", ["1", "0", "0.", "2.286", "0."]),
    ("CQUAD4   1       1       1       2       31      30", ["1", "1", "1", "2", "31", "30"]),
    ("FLFACT*               52              .5              .5", ["52", ".5", ".5", ""]),
    ("FLFACT  3       4774.30\t4815.56", ["3", "4774.30", "4815.56"]),
])
def test_field_access_by_layout(line, fields):
    assert [get_field(line, i + 1) for i in range(len(fields))] == fields
    assert get_field(set_field(line, 2, "NaN"), 2) == "NaN"
    shifted = shift_fields(line, 1, insert=True)
    assert [get_field(shifted, i + 2) for i in range(len(fields) - 1)] == fields[:-1]


@pytest.mark.parametrize("folder", sorted(SEEDS))
def test_seed_decks_run(folder):
    """Unmutated seeds give modes and an aerodynamic model (the fuzz starts from working decks)."""
    main, _ = SEEDS[folder]
    model = read_model(DATA / folder / main)
    assert compute_modes(model, 6)["frequency"].size >= 2
    assert len(read_aero_model(DATA / folder / main).panels) >= 1


@settings(max_examples=200, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(mutated_decks())
def test_mutated_decks_end_in_result_or_named_error(deck):
    check_deck(deck)


@settings(max_examples=150, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(bad_real_values())
def test_one_bad_real_ends_in_result_or_named_error(deck):
    """One real field set to NaN / inf / 0 / 1e300 / its negative: these decks still parse, so
    they reach the project's own value checks, assembly, the eigensolver and the GAFs."""
    check_deck(deck)


@pytest.mark.slow
@settings(max_examples=4000, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(mutated_decks())
def test_mutated_decks_end_in_result_or_named_error_slow(deck):
    check_deck(deck)


@pytest.mark.slow
@settings(max_examples=2000, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(bad_real_values())
def test_one_bad_real_ends_in_result_or_named_error_slow(deck):
    check_deck(deck)
