"""The ECLIPSE summary reader on files written here, record by record, from the format's definition (Fortran
unformatted, big-endian, 16-byte keyword headers, data blocks of <= 1000 numbers / 105 strings)."""

import struct

import numpy as np
import pytest

from spflow.export.eclipse_summary import SummaryFormatError, read_records, read_summary
from spflow.export.opm_run import OpmNotFoundError, flow_executable


def _record(payload: bytes) -> bytes:
    n = struct.pack(">i", len(payload))
    return n + payload + n


def _keyword(name: str, kind: str, values) -> bytes:
    out = _record(name.ljust(8).encode() + struct.pack(">i", len(values)) + kind.encode())
    if kind == "CHAR":
        for i in range(0, len(values), 105):
            out += _record(b"".join(v.ljust(8).encode() for v in values[i:i + 105]))
    else:
        fmt = {"INTE": ">i4", "REAL": ">f4", "DOUB": ">f8"}[kind]
        for i in range(0, len(values), 1000):
            out += _record(np.asarray(values[i:i + 1000], dtype=fmt).tobytes())
    return out


def test_multi_block_arrays_and_strings(tmp_path):
    ints = list(range(2345))  # three data records
    names = [f"N{i}" for i in range(230)]  # three string records
    path = tmp_path / "X.UNRST"
    path.write_bytes(_keyword("BIG", "INTE", ints) + _keyword("NAMES", "CHAR", names)
                     + _keyword("D", "DOUB", [0.1, 2.5]))
    recs = dict(read_records(path))
    assert recs["BIG"].tolist() == ints
    assert recs["NAMES"] == names
    assert recs["D"].tolist() == [0.1, 2.5]


def test_summary_vectors_by_keyword_and_well(tmp_path):
    keys = ["TIME", "FOPT", "WBHP", "WBHP", "BWSAT"]
    wg = [":+:+:+:+", ":+:+:+:+", "INJ", "PROD", ":+:+:+:+"]
    nums = [0, 0, 0, 0, 7]
    (tmp_path / "C.SMSPEC").write_bytes(_keyword("KEYWORDS", "CHAR", keys) + _keyword("WGNAMES", "CHAR", wg)
                                        + _keyword("NUMS", "INTE", nums))
    body = b""
    for step in range(3):
        body += _keyword("SEQHDR", "INTE", [0]) + _keyword("MINISTEP", "INTE", [step])
        body += _keyword("PARAMS", "REAL", [0.5 * (step + 1), 10.0 * step, 201.0 + step, 200.0, 0.2])
    (tmp_path / "C.UNSMRY").write_bytes(body)
    s = read_summary(tmp_path / "C.SMSPEC", tmp_path / "C.UNSMRY")
    assert set(s) == {"TIME", "FOPT", "WBHP:INJ", "WBHP:PROD", "BWSAT:7"}
    np.testing.assert_allclose(s["TIME"], [0.5, 1.0, 1.5])
    np.testing.assert_allclose(s["WBHP:INJ"] - s["WBHP:PROD"], [1.0, 2.0, 3.0])


def test_broken_framing_is_a_clear_error(tmp_path):
    good = _keyword("A", "INTE", [1, 2, 3])
    path = tmp_path / "B.UNSMRY"
    path.write_bytes(good[:-2])
    with pytest.raises(SummaryFormatError, match="B.UNSMRY"):
        read_records(path)


def test_missing_flow_is_a_clear_error(monkeypatch):
    monkeypatch.setenv("PATH", "/nonexistent")
    with pytest.raises(OpmNotFoundError, match="apt-get install libopm-simulators-bin"):
        flow_executable()
