"""exporters._text: integer and fixed-point text rows built in numpy, against Python's formatting."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from exporters import _text


@settings(max_examples=60, deadline=None)
@given(values=hnp.arrays(np.int64, st.tuples(st.integers(0, 40), st.integers(1, 6)),
                         elements=st.one_of(st.integers(0, 12), st.integers(0, 2**62))))
def test_int_rows_equal_percent_d(values):
    c = values.shape[1]
    literals = [b"f "] + [b"//"] * (c - 1) + [b"\n"]
    template = "f " + "//".join(["%d"] * c) + "\n"
    want = "".join(template % tuple(row) for row in values.tolist()).encode()
    assert _text.int_rows(values, literals) == want


@settings(max_examples=60, deadline=None)
@given(values=hnp.arrays(np.float64, st.tuples(st.integers(0, 40), st.just(3)),
                         elements=st.one_of(st.floats(-1, 1), st.sampled_from([0.0, -0.0, 1.0, -1.0, 0.5, 1e-16, -3e-16]))))
def test_fixed_rows_read_back_within_the_last_decimal(values):
    text = _text.fixed_rows(values, [b"vn ", b" ", b" ", b"\n"], 15).decode()
    lines = text.splitlines()
    assert len(lines) == len(values)
    got = np.array([[float(t) for t in line.split()[1:]] for line in lines]).reshape(values.shape)
    assert np.abs(got - values).max(initial=0) <= 0.5e-15 + 2.3e-16
    for line in lines:
        for t in line.split()[1:]:
            assert t != "-0" and not t.endswith(".") and (t in ("0", "1", "-1") or not t.endswith("0"))


def test_fixed_rows_examples():
    rows = np.array([[0.0, -0.0, 1.0], [-1.0, 0.5, -0.25], [0.1, 1 / 3, -2e-16]])
    assert _text.fixed_rows(rows, [b"", b" ", b" ", b"\n"]) == (
        b"0 0 1\n-1 0.5 -0.25\n0.1 0.333333333333333 0\n")


def test_bad_input_is_refused():
    with pytest.raises(ValueError):
        _text.fixed_rows(np.array([[1.5]]), [b"", b""])
    with pytest.raises(ValueError):
        _text.int_rows(np.array([[-1]]), [b"", b""])
    with pytest.raises(ValueError):
        _text.int_rows(np.array([[1, 2]]), [b"", b""])
    assert _text.int_rows(np.zeros((0, 2), dtype=np.int64), [b"", b" ", b""]) == b""


def test_sink_gets_the_same_text_chunk_by_chunk(monkeypatch):
    monkeypatch.setattr(_text, "ROWS_PER_CHUNK", 7)
    rng = np.random.default_rng(1)
    ints = rng.integers(0, 10**6, (50, 3))
    floats = rng.uniform(-1, 1, (50, 3))
    for fn, values in ((_text.int_rows, ints), (_text.fixed_rows, floats)):
        chunks = []
        assert fn(values, [b"<", b",", b",", b">\n"], sink=chunks.append) is None
        assert len(chunks) == 8 and b"".join(chunks) == fn(values, [b"<", b",", b",", b">\n"])
