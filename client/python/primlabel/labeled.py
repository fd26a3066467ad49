"""The class names of a labeled file's `label` values, as the primlabel tools record them: the
header tag `classes` ("# primlabel classes 0:unknown 1:plane ..." in PCD, "comment primlabel
classes ..." in PLY; core/geometry's labeled_cloud.hpp), else the `classes` list of the
<stem>.classes.json the CLI writes beside the file for readers that drop header comments."""

from __future__ import annotations

import json
import os

_HEADER_LINES = 10000  # as the C++ reader: a header is never longer


def header_tags(raw: bytes, ply: bool) -> dict:
    """The primlabel tags of a PCD (ply=False) or PLY header, name -> value text."""
    prefix = b"comment primlabel " if ply else b"# primlabel "
    end = b"end_header" if ply else b"DATA"
    tags = {}
    pos = 0
    for _ in range(_HEADER_LINES):
        if pos >= len(raw):
            break
        stop = raw.find(b"\n", pos)
        stop = len(raw) if stop < 0 else stop
        line = raw[pos:stop].rstrip(b"\r")
        pos = stop + 1
        if line.startswith(prefix):
            name, _, value = line[len(prefix):].decode("utf-8", "replace").partition(" ")
            tags[name] = value
        if line.startswith(end):
            break
    return tags


def _classes_tag(value: str) -> dict | None:
    classes = {}
    for entry in value.split():
        number, sep, name = entry.partition(":")
        if not sep or not number.isdigit() or not name:
            return None  # not the tools' tag: no guess
        classes[int(number)] = name
    return classes or None


def _classes_json(path: str) -> dict | None:
    beside = os.path.splitext(path)[0] + ".classes.json"
    try:
        with open(beside, encoding="utf-8") as f:
            described = json.load(f)
        return {int(c["id"]): str(c["name"]) for c in described["classes"]} or None
    except (OSError, ValueError, KeyError, TypeError):
        return None


def classes(path, raw: bytes | None = None, ply: bool = False) -> dict | None:
    """label id -> class name for a labeled file (its header's tag first, then the JSON beside
    it), or None for a file that says nothing about its labels. `raw`: the file's bytes, when
    already read."""
    path = os.fspath(path)
    if raw is None:
        try:
            with open(path, "rb") as f:
                raw = f.read(1 << 20)
        except OSError:
            return None
    tag = header_tags(raw, ply).get("classes")
    found = _classes_tag(tag) if tag is not None else None
    return found if found is not None else _classes_json(path)
