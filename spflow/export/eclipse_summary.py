"""Reader of ECLIPSE/OPM unformatted summary files (``.SMSPEC`` + ``.UNSMRY``), standard library and numpy only.

The files are sequences of Fortran unformatted records (big-endian): every record is framed by its byte length as
a 4-byte integer before and after. A keyword is a 16-byte header record -- an 8-character name, an int32 element
count and a 4-character type (``INTE``, ``REAL``, ``DOUB``, ``LOGI``, ``CHAR``, ``C0nn``, ``MESS``) -- followed by
its elements in data records of at most 1000 numbers or 105 strings each. The SMSPEC file names the vectors
(``KEYWORDS`` with ``WGNAMES``/``NAMES`` and ``NUMS``); the UNSMRY file holds one ``PARAMS`` array per written
time step, in that order.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from spflow.core.errors import SpflowError

__all__ = ["read_records", "read_summary", "SummaryFormatError"]

_NUMERIC = {"INTE": ">i4", "REAL": ">f4", "DOUB": ">f8", "LOGI": ">i4"}


class SummaryFormatError(SpflowError):
    """A summary file is not a well-formed ECLIPSE unformatted file."""


def _records(data: bytes, source: str):
    pos, n = 0, len(data)
    while pos < n:
        if pos + 4 > n:
            raise SummaryFormatError(f"{source}: truncated record header at byte {pos}")
        (length,) = struct.unpack(">i", data[pos:pos + 4])
        end = pos + 4 + length
        if length < 0 or end + 4 > n or data[end:end + 4] != data[pos:pos + 4]:
            raise SummaryFormatError(f"{source}: bad record framing at byte {pos} (length {length})")
        yield data[pos + 4:end]
        pos = end + 4


def read_records(path) -> list[tuple[str, np.ndarray | list[str]]]:
    """Every keyword of an unformatted ECLIPSE file as ``(name, values)``: numbers as a numpy array, strings as a
    list of right-stripped str."""
    path = Path(path)
    source = str(path)
    records = _records(path.read_bytes(), source)
    out = []
    for head in records:
        if len(head) != 16:
            raise SummaryFormatError(f"{source}: expected a 16-byte keyword header, got {len(head)} bytes")
        name = head[:8].decode("ascii", "replace").strip()
        (count,) = struct.unpack(">i", head[8:12])
        kind = head[12:16].decode("ascii", "replace")
        if kind in _NUMERIC:
            dtype = np.dtype(_NUMERIC[kind])
            chunks, got = [], 0
            while got < count:
                rec = next(records, None)
                if rec is None:
                    raise SummaryFormatError(f"{source}: keyword {name!r} ends after {got} of {count} values")
                chunks.append(np.frombuffer(rec, dtype=dtype))
                got += chunks[-1].size
            values = np.concatenate(chunks) if chunks else np.zeros(0, dtype)
            out.append((name, values.astype(np.float64 if kind in ("REAL", "DOUB") else np.int64)))
        elif kind == "CHAR" or kind.startswith("C0"):
            width = 8 if kind == "CHAR" else int(kind[1:])
            strings = []
            while len(strings) < count:
                rec = next(records, None)
                if rec is None:
                    raise SummaryFormatError(f"{source}: keyword {name!r} ends after {len(strings)} of {count} strings")
                strings += [rec[i:i + width].decode("ascii", "replace").strip() for i in range(0, len(rec), width)]
            out.append((name, strings))
        elif kind == "MESS" and count == 0:
            out.append((name, []))
        else:
            raise SummaryFormatError(f"{source}: keyword {name!r} has unsupported type {kind!r}")
    return out


def read_summary(smspec, unsmry) -> dict[str, np.ndarray]:
    """Summary vectors ``{"TIME": ..., "FOPT": ..., "WBHP:INJ": ...}`` (well/group vectors as ``KEY:NAME``, block
    vectors as ``KEY:NUM``), one value per written time step."""
    spec = dict(read_records(smspec))
    keys = spec.get("KEYWORDS")
    if keys is None:
        raise SummaryFormatError(f"{smspec}: no KEYWORDS array")
    names = spec.get("WGNAMES", spec.get("NAMES", [""] * len(keys)))
    nums = spec.get("NUMS", np.zeros(len(keys), dtype=np.int64))
    labels = []
    for key, name, num in zip(keys, names, nums):
        if key[:1] in ("W", "G") and name and name != ":+:+:+:+":
            labels.append(f"{key}:{name}")
        elif key[:1] in ("B", "C") and num > 0:
            labels.append(f"{key}:{int(num)}")
        else:
            labels.append(key)
    rows = [values for name, values in read_records(unsmry) if name == "PARAMS"]
    if not rows:
        raise SummaryFormatError(f"{unsmry}: no PARAMS arrays (no time step written)")
    table = np.vstack(rows)
    if table.shape[1] != len(labels):
        raise SummaryFormatError(f"{unsmry}: PARAMS has {table.shape[1]} values, {smspec} names {len(labels)}")
    return {label: table[:, i] for i, label in enumerate(labels) if label not in ("", ":+:+:+:+")}
