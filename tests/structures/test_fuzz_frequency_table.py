"""Fuzz test of the frequency-table reader: damaged CSV tables end in a GVT Dataset or an
InputError.

Seed: a published-style table (comment, header in another order, names, a blank damping).
Mutations: truncation at any byte, a field replaced by text / NaN / inf / a negative or
fractional number / nothing, a comma added or removed, lines duplicated or deleted, and any
bytes (a binary file). Property: :func:`structures.gvt.read_frequency_table` returns a valid
Dataset of frequencies alone, or raises :class:`InputError` whose message names the file;
never another exception.
"""
from __future__ import annotations

import re
import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from structures.common.errors import InputError
from structures.gvt import read_frequency_table, validate_gvt

SEED = (b"# X-56-like GVT, published table\r\nname, mode, frequency, damping\r\n"
        b"SW1B, 7, 5.42, 0.012\nAW1B, 8, 6.875, 0.0095\nSW1T, 9, 1.2e1,\nFUS1, 11, 14.0, 0.02\n")
NAME = "fuzzed_modes.csv"
_FIELD = re.compile(rb"[^,\r\n]+")


@st.composite
def _truncate(draw, data):
    return data[:draw(st.integers(0, len(data)))]


@st.composite
def _replace_field(draw, data):
    spans = [m.span() for m in _FIELD.finditer(data)]
    if not spans:
        return data
    start, end = spans[draw(st.integers(0, len(spans) - 1))]
    value = draw(st.sampled_from([b"NaN", b"inf", b"-1.0", b"7.5", b"abc", b"", b" ", b"1e400",
                                  b"mode", b"frequency", b"0x10", b"\xff\xfe", b"1e300", b"0"]))
    return data[:start] + value + data[end:]


@st.composite
def _comma(draw, data):
    i = draw(st.integers(0, len(data)))
    if draw(st.booleans()):
        return data[:i] + b"," + data[i:]
    j = data.find(b",", i)
    return data if j < 0 else data[:j] + data[j + 1:]


@st.composite
def _lines(draw, data):
    lines = data.splitlines(keepends=True)
    if not lines:
        return data
    i = draw(st.integers(0, len(lines) - 1))
    return b"".join(lines[:i] + ([lines[i]] * 2 if draw(st.booleans()) else []) + lines[i + 1:])


MUTATIONS = (_truncate, _replace_field, _comma, _lines)


@st.composite
def damaged_tables(draw):
    if draw(st.integers(0, 9)) == 0:
        return draw(st.binary(max_size=200))
    data = SEED
    for _ in range(draw(st.integers(1, 3))):
        data = draw(draw(st.sampled_from(MUTATIONS))(data))
    return data


@settings(max_examples=300, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(damaged_tables())
def test_damaged_table_gives_dataset_or_input_error(data):
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / NAME
        path.write_bytes(data)
        try:
            ds = read_frequency_table(path)
        except InputError as exc:
            assert NAME in str(exc), str(exc)
            return
    validate_gvt(ds, shapes=False)
    assert ds.sizes["mode"] >= 1 and "shape" not in ds
