"""The tensor file: the container of RGL ``.bsdf`` materials (Mitsuba 3's ``TensorFile``).

Layout (little-endian), as Mitsuba 3's ``src/core/tensor.cpp`` reads it:

===========  ==========================================================================
bytes        content
===========  ==========================================================================
12           ``b"tensor_file\\0"``
2            version, ``(1, 0)``
4            uint32: number of fields
per field    uint16 name length, the UTF-8 name, uint16 ndim, uint8 dtype code,
             uint64 byte offset of the data, ndim x uint64 shape
data         each field's C-ordered array at its offset (we align offsets to 8 bytes)
===========  ==========================================================================

dtype codes: 1 uint8, 2 int8, 3 uint16, 4 int16, 5 uint32, 6 int32, 7 uint64, 8 int64,
9 float16, 10 float32, 11 float64.

Reading checks every size and offset against the file before touching the data, so a
truncated or corrupt file is a ``ValueError`` naming the field, never a crash or a huge
allocation.
"""
from __future__ import annotations

import os
import struct

import numpy as np

from bsdflab.util.files import write_atomically

MAGIC = b"tensor_file\0"
VERSION = (1, 0)
DTYPES = {1: np.uint8, 2: np.int8, 3: np.uint16, 4: np.int16, 5: np.uint32, 6: np.int32,
          7: np.uint64, 8: np.int64, 9: np.float16, 10: np.float32, 11: np.float64}
CODES = {np.dtype(v): k for k, v in DTYPES.items()}
ALIGN = 8
# Caps that keep a hostile header from asking for absurd work before any data is read.
MAX_FIELDS = 64
MAX_NDIM = 8
MAX_FILE_BYTES = 1 << 31


def read_tensor_file(path) -> dict[str, np.ndarray]:
    """Read every field of the tensor file at ``path`` (str or path) into numpy arrays.

    Raises ``ValueError`` naming the file and the field for a missing file, a wrong
    magic or version, a truncated header, an unknown dtype, or data outside the file."""
    path = os.fspath(path)
    try:
        size = os.path.getsize(path)
    except OSError as e:
        raise ValueError(f"{path}: cannot read the tensor file ({e.strerror})") from None
    if size > MAX_FILE_BYTES:
        raise ValueError(f"{path}: {size} bytes is larger than the {MAX_FILE_BYTES}-byte cap on tensor files")
    with open(path, "rb") as f:
        data = f.read()
    return parse_tensor_file(data, name=path)


def parse_tensor_file(data: bytes, name: str = "tensor file") -> dict[str, np.ndarray]:
    """The fields of a tensor file held in memory (``data``); see ``read_tensor_file``."""
    pos = 0

    def take(n: int, what: str) -> bytes:
        nonlocal pos
        if pos + n > len(data):
            raise ValueError(f"{name}: truncated while reading {what} (needs byte {pos + n}, "
                             f"the file has {len(data)})")
        out = data[pos:pos + n]
        pos += n
        return out

    if len(data) < len(MAGIC) or data[:len(MAGIC)] != MAGIC:
        raise ValueError(f"{name}: not a tensor file (the magic 'tensor_file\\0' is missing)")
    pos = len(MAGIC)
    version = tuple(take(2, "the version"))
    if version != VERSION:
        raise ValueError(f"{name}: tensor file version {version[0]}.{version[1]}; "
                         f"this reader reads version {VERSION[0]}.{VERSION[1]}")
    (n_fields,) = struct.unpack("<I", take(4, "the field count"))
    if n_fields > MAX_FIELDS:
        raise ValueError(f"{name}: {n_fields} fields; at most {MAX_FIELDS} are accepted")
    fields: dict[str, np.ndarray] = {}
    for k in range(n_fields):
        (n_name,) = struct.unpack("<H", take(2, f"the name length of field {k}"))
        raw = take(n_name, f"the name of field {k}")
        try:
            field = raw.decode("utf-8")
        except UnicodeDecodeError:
            raise ValueError(f"{name}: the name of field {k} is not UTF-8") from None
        ndim, code, offset = struct.unpack("<HBQ", take(11, f"the header of field {field!r}"))
        if code not in DTYPES:
            raise ValueError(f"{name}: field {field!r} has unknown dtype code {code} (known: 1-11)")
        if ndim > MAX_NDIM:
            raise ValueError(f"{name}: field {field!r} has {ndim} dimensions; at most {MAX_NDIM}")
        shape = struct.unpack(f"<{ndim}Q", take(8 * ndim, f"the shape of field {field!r}"))
        dtype = np.dtype(DTYPES[code]).newbyteorder("<")
        count = 1
        for s in shape:
            count *= int(s)
            if count * dtype.itemsize > len(data):
                break
        nbytes = count * dtype.itemsize
        if offset > len(data) or nbytes > len(data) - offset:
            raise ValueError(f"{name}: field {field!r} (shape {tuple(int(s) for s in shape)}, "
                             f"{dtype.name}) lies outside the file: truncated or corrupt")
        if field in fields:
            raise ValueError(f"{name}: field {field!r} appears twice")
        array = np.frombuffer(data, dtype=dtype, count=count, offset=int(offset))
        fields[field] = array.reshape(tuple(int(s) for s in shape)).astype(dtype.newbyteorder("="))
    return fields


def tensor_file_bytes(fields: dict[str, np.ndarray]) -> bytes:
    """The bytes of a tensor file holding ``fields`` (name -> array, in order); str values
    are stored as uint8 (UTF-8)."""
    arrays = {}
    for key, value in fields.items():
        a = np.frombuffer(value.encode("utf-8"), dtype=np.uint8) if isinstance(value, str) else np.asarray(value)
        if np.dtype(a.dtype) not in CODES:
            raise ValueError(f"field {key!r}: dtype {a.dtype} cannot be stored in a tensor file")
        arrays[key] = np.ascontiguousarray(a, dtype=a.dtype.newbyteorder("<"))
    header = bytearray(MAGIC + bytes(VERSION) + struct.pack("<I", len(arrays)))
    slots = {}
    for key, a in arrays.items():
        label = key.encode("utf-8")
        header += struct.pack("<H", len(label)) + label
        header += struct.pack("<HB", a.ndim, CODES[np.dtype(a.dtype).newbyteorder("=")])
        slots[key] = len(header)
        header += struct.pack("<Q", 0) + struct.pack(f"<{a.ndim}Q", *a.shape)
    body = bytearray(header)
    for key, a in arrays.items():
        start = (len(body) + ALIGN - 1) // ALIGN * ALIGN
        body += b"\0" * (start - len(body))
        body[slots[key]:slots[key] + 8] = struct.pack("<Q", start)
        body += a.tobytes()
    return bytes(body)


def write_tensor_file(path, fields: dict[str, np.ndarray]) -> None:
    """Write ``fields`` to ``path`` atomically (a temporary, then a rename)."""
    payload = tensor_file_bytes(fields)

    def write(tmp: str) -> None:
        with open(tmp, "wb") as f:
            f.write(payload)

    write_atomically(path, write, suffix=".tmp.bsdf")
