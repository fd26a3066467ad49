"""LZF decompression (the format of liblzf, which PCD's DATA binary_compressed uses), in pure
Python: a control byte below 32 starts a literal run of ctrl + 1 bytes; otherwise its top three
bits (7: plus the next byte) give a back-reference of length + 2 bytes, at a distance from its
low five bits and the next byte.

Both directions go through Debian's liblzf1, the library the C++ side links, loaded with ctypes
when it is there: pure Python takes a fraction of a second to decompress a frame and would take
seconds to compress one. Without it, decompression falls back to Python and compress() raises
LzfError (ascii and binary PCD are still written)."""

from __future__ import annotations

import ctypes
import ctypes.util
import functools


class LzfError(ValueError):
    pass


# PCD stores the sizes as uint32 and lzf_compress takes unsigned int ones; the output may be
# 1/32 larger than the input, so the input stays well below 4 GiB.
_MAX_BLOCK = 0xF0000000


@functools.lru_cache(maxsize=1)
def _liblzf():
    for name in ("liblzf.so.1", ctypes.util.find_library("lzf")):
        if not name:
            continue
        try:
            library = ctypes.CDLL(name)
        except OSError:
            continue
        library.lzf_compress.argtypes = [ctypes.c_void_p, ctypes.c_uint, ctypes.c_void_p,
                                         ctypes.c_uint]
        library.lzf_compress.restype = ctypes.c_uint
        library.lzf_decompress.argtypes = library.lzf_compress.argtypes
        library.lzf_decompress.restype = ctypes.c_uint
        return library
    return None


def can_compress() -> bool:
    """Whether liblzf is there for compress()."""
    return _liblzf() is not None


def compress(data: bytes) -> bytes:
    """`data` LZF-compressed by liblzf. Incompressible data grows by at most one control byte per
    32 bytes (liblzf's literal runs), so the output buffer always suffices."""
    library = _liblzf()
    if library is None:
        raise LzfError("writing binary_compressed PCD needs liblzf (Debian: apt-get install "
                       "liblzf1)")
    if not data:
        return b""
    if len(data) > _MAX_BLOCK:
        raise LzfError(f"{len(data)} bytes is more than one LZF block holds ({_MAX_BLOCK})")
    capacity = len(data) + len(data) // 32 + 16
    source = ctypes.create_string_buffer(bytes(data), len(data))
    target = ctypes.create_string_buffer(capacity)
    size = library.lzf_compress(source, len(data), target, capacity)
    if size == 0:
        raise LzfError(f"liblzf could not compress {len(data)} bytes into {capacity}")
    return target.raw[:size]


def decompress(data: bytes, expected_size: int) -> bytes:
    """The `expected_size` bytes `data` decompresses to; LzfError if it is corrupt, decompresses
    to another size or refers before its start. Never grows past expected_size. Through liblzf
    when it is there (milliseconds a frame), else in Python."""
    library = _liblzf()
    if library is None or expected_size == 0:
        return decompress_python(data, expected_size)
    source = ctypes.create_string_buffer(bytes(data), len(data))
    # One byte of slack: liblzf fails with E2BIG when the data decompresses to more than fits,
    # so output beyond expected_size is seen as a size mismatch, never written past the buffer.
    target = ctypes.create_string_buffer(expected_size + 1)
    size = library.lzf_decompress(source, len(data), target, expected_size + 1)
    if size == 0 and data:
        raise LzfError("corrupt LZF data (liblzf refused it: a run or back-reference out of "
                       "bounds, or more than the expected size)")
    if size != expected_size:
        raise LzfError(f"decompresses to {size} bytes, expected {expected_size}")
    return target.raw[:size]


def decompress_python(data: bytes, expected_size: int) -> bytes:
    """decompress() in pure Python, where liblzf is missing."""
    out = bytearray()
    pos, end = 0, len(data)
    while pos < end:
        ctrl = data[pos]
        pos += 1
        if ctrl < 32:
            length = ctrl + 1
            if pos + length > end:
                raise LzfError(f"literal run of {length} bytes past the end of the data")
            if len(out) + length > expected_size:
                raise LzfError(f"decompresses to more than {expected_size} bytes")
            out += data[pos : pos + length]
            pos += length
            continue
        length = ctrl >> 5
        if length == 7:
            if pos >= end:
                raise LzfError("back-reference cut off at the end of the data")
            length += data[pos]
            pos += 1
        length += 2
        if pos >= end:
            raise LzfError("back-reference cut off at the end of the data")
        distance = ((ctrl & 0x1F) << 8) + data[pos] + 1
        pos += 1
        start = len(out) - distance
        if start < 0:
            raise LzfError(f"back-reference {distance} bytes before the start of the output")
        if len(out) + length > expected_size:
            raise LzfError(f"decompresses to more than {expected_size} bytes")
        if distance >= length:
            out += out[start : start + length]
        else:  # overlapping: the last `distance` bytes repeat
            pattern = out[start:]
            out += (pattern * (length // distance + 1))[:length]
    if len(out) != expected_size:
        raise LzfError(f"decompresses to {len(out)} bytes, expected {expected_size}")
    return bytes(out)
