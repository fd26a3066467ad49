"""LZF decompression (the format of liblzf, which PCD's DATA binary_compressed uses), in pure
Python: a control byte below 32 starts a literal run of ctrl + 1 bytes; otherwise its top three
bits (7: plus the next byte) give a back-reference of length + 2 bytes, at a distance from its
low five bits and the next byte."""

from __future__ import annotations


class LzfError(ValueError):
    pass


def decompress(data: bytes, expected_size: int) -> bytes:
    """The `expected_size` bytes `data` decompresses to; LzfError if it is corrupt, decompresses
    to another size or refers before its start. Never grows past expected_size."""
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
