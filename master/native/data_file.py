"""The data file of a native FMU (``resources/model.pcsdata``, read by
``fmus/native/pcs_data.c``): the constants the Python models compute at export, with a
header that lets the FMU refuse a damaged or foreign file. Integers are little-endian on the
hosts the FMUs are built for (the byte-order mark tells):

====================  ==========================================================
header, 40 bytes      ``PCSDATA\\0``, uint32 version (1), uint32 byte-order mark
                      0x01020304, uint32 model kind (``PCS_KIND_`` of pcs_data.h:
                      1 linear catenary, 2 modal catenary, 3 lumped pantograph, 4
                      rigid DSA-380, 5 flexible DSA-380), uint32 sections, uint64
                      payload bytes, uint64 FNV-1a 64 checksum of the payload
section, 40 + data    char name[24] (NUL padded), uint32 type (1 float64, 2 int32),
                      uint32 0, uint64 count, the values padded to 8 bytes
====================  ==========================================================
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numba import njit

from pantocosim.core.errors import ParameterError
from pantocosim.master.native.headers import kind as kind_code

MAGIC = b"PCSDATA\0"
VERSION = 1
BYTE_ORDER_MARK = 0x01020304
KINDS = {"linear": kind_code("LINEAR_CATENARY"), "modal": kind_code("MODAL_CATENARY"),
         "lumped": kind_code("LUMPED_PANTOGRAPH"), "dsa380-rigid": kind_code("DSA380_RIGID"),
         "dsa380-flexible": kind_code("DSA380_FLEXIBLE")}
TYPES = {np.dtype(np.float64): 1, np.dtype(np.int32): 2}
DATA_FILE = "model.pcsdata"


@njit(cache=True)
def _fnv1a(arr):
    h = np.uint64(14695981039346656037)
    prime = np.uint64(1099511628211)
    for b in arr:
        h = (h ^ np.uint64(b)) * prime
    return h


def fnv1a(data: bytes) -> int:
    """FNV-1a 64 (the data file's checksum)."""
    return int(_fnv1a(np.frombuffer(data, dtype=np.uint8)))


def pack_data(kind: str, sections: dict) -> bytes:
    """The data file of ``sections`` {name: float64 or int32 array}."""
    parts = []
    for name, values in sections.items():
        arr = np.ascontiguousarray(values)
        if arr.dtype not in TYPES:
            raise TypeError(f"section {name}: {arr.dtype} (float64 or int32 only)")
        if len(name.encode()) > 23:
            raise ValueError(f"section name {name!r} longer than 23 bytes")
        body = arr.astype(arr.dtype.newbyteorder("<")).tobytes()
        body += b"\0" * (-len(body) % 8)
        parts.append(name.encode().ljust(24, b"\0")
                     + np.array([TYPES[arr.dtype], 0], "<u4").tobytes()
                     + np.array([arr.size], "<u8").tobytes() + body)
    payload = b"".join(parts)
    head = (MAGIC + np.array([VERSION, BYTE_ORDER_MARK, KINDS[kind], len(sections)],
                             "<u4").tobytes()
            + np.array([len(payload), fnv1a(payload)], "<u8").tobytes())
    return head + payload


def write_data(path: Path, kind: str, sections: dict) -> bytes:
    data = pack_data(kind, sections)
    Path(path).write_bytes(data)
    return data


def read_data(path: Path) -> tuple[str, dict]:
    """(kind, sections) of a data file (for tests and inspection), checked as the C reader
    checks it."""
    raw = Path(path).read_bytes()
    if raw[:8] != MAGIC:
        raise ParameterError(str(path), raw[:8], "not a pantocosim data file")
    version, bom, kind, count = np.frombuffer(raw[8:24], "<u4")
    size, checksum = np.frombuffer(raw[24:40], "<u8")
    payload = raw[40:]
    if version != VERSION or bom != BYTE_ORDER_MARK or size != len(payload) \
            or checksum != fnv1a(payload):
        raise ParameterError(str(path), "header", "wrong version, byte order, size or checksum")
    out, pos = {}, 40
    for _ in range(int(count)):
        name = raw[pos:pos + 24].rstrip(b"\0").decode()
        typ = int(np.frombuffer(raw[pos + 24:pos + 28], "<u4")[0])
        n = int(np.frombuffer(raw[pos + 32:pos + 40], "<u8")[0])
        dtype = np.dtype("<f8") if typ == 1 else np.dtype("<i4")
        nbytes = n * dtype.itemsize
        out[name] = np.frombuffer(raw[pos + 40:pos + 40 + nbytes], dtype).copy()
        pos += 40 + nbytes + (-nbytes % 8)
    kinds = {v: k for k, v in KINDS.items()}
    return kinds[int(kind)], out
