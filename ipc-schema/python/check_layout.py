#!/usr/bin/env python3
"""Compares the ctypes mirror cablevib_ipc.py with a JSON export of the Rust layout table.

    python3 check_layout.py LAYOUT.json

LAYOUT.json (written by cli/tests/ipc/python_controller.rs of the workspace root from
cablevib_ipc::layout::ALL_LAYOUTS and the crate's constants) holds
{"structs": [{"rust_name", "type_name", "size", "align", "fields": [{"name", "offset",
"size", "elem", "len"}]}], "constants": {NAME: value}}. Every struct must have the same
ctypes.sizeof, ctypes.alignment, type_name(), field names in the same order, and each field the
same offset, size, element type and length; every constant the same value. Prints each
difference and exits with 1, or prints a one-line summary and exits with 0.
"""

import ctypes
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import cablevib_ipc as cv  # noqa: E402

ELEM = {"u32": ctypes.c_uint32, "u64": ctypes.c_uint64, "f64": ctypes.c_double}


def field_problems(cls, f):
    """Differences of field f (a JSON object) of ctypes struct cls."""
    name = cls.__name__ + "." + f["name"]
    d = getattr(cls, f["name"], None)
    if d is None:
        return [name + ": missing"]
    out = []
    if (d.offset, d.size) != (f["offset"], f["size"]):
        out.append("%s: offset %d size %d, Rust offset %d size %d" % (name, d.offset, d.size, f["offset"], f["size"]))
    ctype = dict(cls._fields_)[f["name"]]
    elem, length = (ctype._type_, ctype._length_) if hasattr(ctype, "_length_") else (ctype, 1)
    if (elem, length) != (ELEM[f["elem"]], f["len"]):
        out.append("%s: %s x %d, Rust %s x %d" % (name, elem.__name__, length, f["elem"], f["len"]))
    return out


def struct_problems(s):
    cls = getattr(cv, s["rust_name"], None)
    if cls is None:
        return [s["rust_name"] + ": missing"]
    out = []
    if (ctypes.sizeof(cls), ctypes.alignment(cls)) != (s["size"], s["align"]):
        out.append("%s: size %d align %d, Rust size %d align %d" % (
            s["rust_name"], ctypes.sizeof(cls), ctypes.alignment(cls), s["size"], s["align"]))
    if cls.type_name() != s["type_name"]:
        out.append("%s: type_name %r, Rust %r" % (s["rust_name"], cls.type_name(), s["type_name"]))
    names = [f[0] for f in cls._fields_]
    if names != [f["name"] for f in s["fields"]]:
        out.append("%s: fields %s, Rust %s" % (s["rust_name"], names, [f["name"] for f in s["fields"]]))
    for f in s["fields"]:
        out.extend(field_problems(cls, f))
    return out


def main():
    with open(sys.argv[1]) as fh:
        table = json.load(fh)
    problems = []
    for s in table["structs"]:
        problems.extend(struct_problems(s))
    for name, value in table["constants"].items():
        if getattr(cv, name, None) != value:
            problems.append("constant %s: %r, Rust %r" % (name, getattr(cv, name, None), value))
    for p in problems:
        print("mismatch: " + p)
    if problems:
        return 1
    fields = sum(len(s["fields"]) for s in table["structs"])
    print("layout ok: %d structs, %d fields, %d constants" % (len(table["structs"]), fields, len(table["constants"])))
    return 0


if __name__ == "__main__":
    sys.exit(main())
