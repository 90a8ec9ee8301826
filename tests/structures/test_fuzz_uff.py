"""Fuzz test of the UFF reader: damaged universal files end in a GVT Dataset or an InputError.

Seeds are the shipped example's GVT (``data/bah_wing/gvt.unv``, pyuff layout) and the vendor file
(``tests/data/gvt/vendor_modes.unv``: CRLF, D exponents, free columns). Mutations: truncation at
any byte, a number replaced by NaN / inf / text, a dataset number changed, lines duplicated or
deleted, and CRLF / D-exponent variants of the whole file. Property: :func:`structures.gvt.read_uff`
returns a valid Dataset, or raises :class:`InputError` whose message names the file; never another
exception.
"""
from __future__ import annotations

import re
import tempfile
import warnings
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from structures.common.errors import InputError
from structures.gvt import read_uff, validate_gvt

ROOT = Path(__file__).resolve().parents[2]
SEEDS = {"bah": (ROOT / "data" / "bah_wing" / "gvt.unv").read_bytes(),
         "vendor": (ROOT / "tests" / "data" / "gvt" / "vendor_modes.unv").read_bytes()}
NAME = "fuzzed_modes.unv"
_NUMBER = re.compile(rb"[-+]?\d*\.\d+(?:[eEdD][-+]?\d+)?")


def _truncate(data: bytes, draw) -> bytes:
    return data[:draw(st.integers(0, len(data)))]


def _replace_number(data: bytes, draw) -> bytes:
    spans = [m.span() for m in _NUMBER.finditer(data)]
    if not spans:
        return data
    start, end = spans[draw(st.integers(0, len(spans) - 1))]
    value = draw(st.sampled_from([b"NaN", b"nan", b"inf", b"-Infinity", b"abc", b"1.0.0", b"",
                                  b"9.99E+999", b"--1.0"]))
    return data[:start] + value + data[end:]


def _dataset_number(data: bytes, draw) -> bytes:
    lines = data.splitlines(keepends=True)
    heads = [i + 1 for i, ln in enumerate(lines[:-1]) if ln.strip() == b"-1"]
    if not heads:
        return data
    i = draw(st.sampled_from(heads))
    number = draw(st.sampled_from([b"58", b"15", b"55", b"2411", b"151", b"164", b"2414b", b"0",
                                   b"x55", b"-1"]))
    return b"".join(lines[:i] + [b"    " + number + b"\n"] + lines[i + 1:])


def _duplicate_or_delete(data: bytes, draw) -> bytes:
    lines = data.splitlines(keepends=True)
    if not lines:
        return data
    i = draw(st.integers(0, len(lines) - 1))
    return b"".join(lines[:i] + ([lines[i]] * 2 if draw(st.booleans()) else []) + lines[i + 1:])


def _variant(data: bytes, draw) -> bytes:
    if draw(st.booleans()):
        data = data.replace(b"\r\n", b"\n").replace(b"\n", b"\r\n")
    if draw(st.booleans()):
        data = re.sub(rb"(\d)[eE]([-+]\d)", rb"\1D\2", data)
    return data


MUTATIONS = (_truncate, _replace_number, _dataset_number, _duplicate_or_delete, _variant)


@st.composite
def damaged_files(draw) -> bytes:
    data = SEEDS[draw(st.sampled_from(sorted(SEEDS)))]
    for _ in range(draw(st.integers(1, 3))):
        data = draw(st.sampled_from(MUTATIONS))(data, draw)
    return data


def _check(data: bytes) -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / NAME
        path.write_bytes(data)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ds = read_uff(path)
        except InputError as exc:
            assert NAME in str(exc), str(exc)
            return
    validate_gvt(ds)
    assert ds.sizes["mode"] >= 1 and ds.sizes["dof"] >= 1


@settings(max_examples=200, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(damaged_files())
def test_damaged_uff_gives_dataset_or_input_error(data):
    _check(data)


@pytest.mark.slow
@settings(max_examples=3000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(damaged_files())
def test_damaged_uff_gives_dataset_or_input_error_many(data):
    _check(data)


@pytest.mark.parametrize("cut", [0.25, 0.5, 0.75, 0.95])
def test_file_cut_inside_a_mode_is_refused(cut, tmp_path):
    """The issue's case: a file cut inside a mode was read with the modes before the cut."""
    data = SEEDS["bah"]
    path = tmp_path / "cut.unv"
    path.write_bytes(data[:int(cut * len(data))])
    with pytest.raises(InputError, match=r"cut\.unv, dataset #\d+ \(line \d+\): no closing -1"):
        read_uff(path)


def test_nan_and_text_name_the_mode_node_and_line(tmp_path):
    text = SEEDS["bah"].decode()
    lines = text.splitlines(keepends=True)
    # line 122 holds the values of node 19 in the second mode (the dataset 55 starting at line 76)
    assert lines[120].strip() == "19" and lines[75].strip() == "55"
    for value, message in (("NaN", r"nan\.unv, mode 2: NaN/inf in the shape at nodes \[19\]"),
                           ("-inf", r"nan\.unv, mode 2: NaN/inf in the shape at nodes \[19\]"),
                           ("abc", r"nan\.unv, dataset #3 \(55, line 76\), line 122: 'abc' is not "
                                   r"a number")):
        bad = lines[:121] + [re.sub(r"^\s*\S+", " " + value, lines[121])] + lines[122:]
        (tmp_path / "nan.unv").write_text("".join(bad))
        with pytest.raises(InputError, match=message):
            read_uff(tmp_path / "nan.unv")


def test_unknown_dataset_number_is_refused(tmp_path):
    text = re.sub(r"(?m)^(\s*)55(\s*)$", r"\g<1>58\2", SEEDS["bah"].decode(), count=1)
    (tmp_path / "g.unv").write_text(text)
    with pytest.raises(InputError, match=r"g\.unv, dataset #2 \(line 25\): dataset 58 is not a "
                                         r"dataset this reader knows.*Fix:"):
        read_uff(tmp_path / "g.unv")


def test_node_record_with_a_value_missing_is_refused(tmp_path):
    lines = SEEDS["bah"].decode().splitlines(keepends=True)
    bad = lines[:121] + [" ".join(lines[121].split()[:2]) + "\n"] + lines[122:]
    (tmp_path / "short.unv").write_text("".join(bad))
    with pytest.raises(InputError, match=r"short\.unv, dataset #3 \(55, line 76\), mode 2: \d+ "
                                         r"numbers do not make whole node records"):
        read_uff(tmp_path / "short.unv")
