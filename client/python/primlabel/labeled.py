"""The class names of a labeled file's `label` values, as the primlabel tools record them: the
header tag `classes` ("# primlabel classes 0:unknown 1:plane ..." in PCD, "comment primlabel
classes ..." in PLY; core/geometry's labeled_cloud.hpp), else the `classes` list of the
<stem>.classes.json the CLI writes beside the file for readers that drop header comments."""

from __future__ import annotations

import json
import os

from . import _cloud_files


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
    it), or None for a file that says nothing about its labels. The tags are read by the C++
    reader (read_cloud_tags), which tells a PLY by its extension: `raw` and `ply` are accepted
    as before and no longer needed."""
    del raw, ply
    path = os.fspath(path)
    try:
        tag = _cloud_files.read_tags(path).get("classes")
    except _cloud_files.IoError:
        return None
    found = _classes_tag(tag) if tag is not None else None
    return found if found is not None else _classes_json(path)
