# SPDX-License-Identifier: Apache-2.0
"""RIHS01 type hashes (REP-2011) computed from .msg definitions, written from the algorithm in
rosidl_generator_type_description (../shared/docs/dds.md §3.4): per type its fields in .msg
order, each {type_id, capacity, string_capacity, nested_type_name}; the referenced types sorted
by name; json.dumps with ', ' and ': ' separators; SHA-256. Run as a script it prints every hash."""
import hashlib
import json

from ros2_msg_defs import MSGS, PRIMITIVES, dependencies, fields

TYPE_ID = {"int8": 2, "uint8": 3, "int16": 4, "uint16": 5, "int32": 6, "uint32": 7, "int64": 8,
           "uint64": 9, "float32": 10, "float64": 11, "bool": 15,
           # rosidl turns a .msg char into an IDL uint8 before describing the type
           "char": 3,
           "byte": 16, "string": 17, "wstring": 18}
NESTED, BOUNDED_STRING = 1, 21
ARRAY_OFFSET = {None: 0, "fixed": 48, "bounded": 96, "unbounded": 144}


def _field(name, base, arr, sbound):
    if base in PRIMITIVES:
        tid = BOUNDED_STRING if base == "string" and sbound else TYPE_ID[base]
        nested = ""
    else:
        tid, nested = NESTED, base
    kind, cap = arr if arr else (None, 0)
    return {"name": name, "type": {"type_id": tid + ARRAY_OFFSET[kind], "capacity": cap,
                                   "string_capacity": sbound, "nested_type_name": nested}}


def _description(type_name):
    return {"type_name": type_name, "fields": [_field(*f) for f in fields(type_name)]}


def rihs01(type_name):
    doc = {"type_description": _description(type_name),
           "referenced_type_descriptions": [_description(d) for d in dependencies(type_name)]}
    text = json.dumps(doc, ensure_ascii=True, indent=None, separators=(", ", ": "), sort_keys=False)
    return "RIHS01_" + hashlib.sha256(text.encode("utf-8")).hexdigest()


if __name__ == "__main__":
    for n in MSGS:
        print(f"{n:44s} {rihs01(n)}")
