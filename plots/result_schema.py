"""The result schema (harness/run/result_schema.json), read by the Python side.

The same file is compiled into the runner (harness/run/result_schema.hpp): the writer is tested
against it, `bvhbench compare` validates with it and `summary.csv` takes its columns from it.
Here it serves the report's readers: `Job.get` refuses a path the schema does not describe (a
reader that asks for a field nobody writes is a bug, found by the first test that runs it), and
`problems()` says where a result file departs from it. Standard library only.
"""
import json
import os

SCHEMA_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "harness", "run",
                           "result_schema.json")


class SchemaError(Exception):
    """A reader asked for a field the schema does not describe (a programming error)."""


def _load():
    with open(SCHEMA_FILE, encoding="utf-8") as fh:
        return json.load(fh)


_SCHEMA = _load()
VERSION = _SCHEMA["schema"]
FIELDS = _SCHEMA["fields"]                 # dotted path -> {type, required, doc}
SUMMARY_COLUMNS = _SCHEMA["summary_csv"]   # [{column, field | ratio | share, or_stem_of?}]
STATUSES = tuple(FIELDS["status"]["enum"])  # the job statuses: the schema's one list of them
_PATTERNS = [(tuple(p.split(".")), p) for p in FIELDS]


def _matches(pattern, keys):
    return len(pattern) == len(keys) and all(a in ("*", b) for a, b in zip(pattern, keys))


def describe(path):
    """The schema's entry for a dotted path, or None: an exact entry first, else one with '*'
    for keys, else a free-form ('any') ancestor."""
    if path in FIELDS:
        return FIELDS[path]
    keys = tuple(path.split("."))
    for pattern, name in _PATTERNS:
        if _matches(pattern, keys):
            return FIELDS[name]
    for n in range(len(keys) - 1, 0, -1):
        for pattern, name in _PATTERNS:
            if _base(FIELDS[name]["type"]) == "any" and _matches(pattern, keys[:n]):
                return FIELDS[name]
    return None


def require_described(path):
    if describe(path) is None:
        raise SchemaError(f"result field {path!r} is not in {os.path.relpath(SCHEMA_FILE)}; "
                          "add it there (and to the writer) or read another field")


def _base(t):
    return t[:-5] if t.endswith("|null") else t


def has_type(value, t):
    if value is None:
        return t.endswith("|null") or _base(t) == "any"
    t = _base(t)
    if t == "any":
        return True
    if t == "string":
        return isinstance(value, str)
    if t == "integer":
        return isinstance(value, int) and not isinstance(value, bool)
    if t == "number":
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if t == "boolean":
        return isinstance(value, bool)
    if t == "object":
        return isinstance(value, dict)
    if t.startswith("array<") and t.endswith(">"):
        item = t[6:-1]
        return isinstance(value, list) and all(x is not None and has_type(x, item) for x in value)
    return False


def _walk(value, prefix=""):
    """(dotted path, value) of every key of nested objects."""
    if isinstance(value, dict):
        for k, v in value.items():
            path = f"{prefix}.{k}" if prefix else k
            yield path, v
            entry = describe(path)
            if entry is None or _base(entry["type"]) != "any":
                yield from _walk(v, path)


def problems(result):
    """Where a result departs from the schema, as messages ([] when it follows it): values of
    another type, required fields missing where their parent is present, and values the schema
    does not describe."""
    out = []
    if not isinstance(result, dict):
        return ["not a JSON object"]
    if result.get("schema") != VERSION:
        out.append(f"schema is {result.get('schema')!r}, not {VERSION!r}")
    ok = result.get("status") == "ok"
    for path, value in _walk(result):
        entry = describe(path)
        if entry is None:
            out.append(f"{path}: not described by the schema")
        elif not has_type(value, entry["type"]):
            out.append(f"{path}: must be {entry['type']}")
        elif "enum" in entry and isinstance(value, str) and value not in entry["enum"]:
            out.append(f"{path}: {value!r} is none of {', '.join(entry['enum'])}")
    for path, entry in FIELDS.items():
        keys = path.split(".")
        if "*" in keys or entry["required"] == "optional":
            continue
        if entry["required"] == "ok" and not ok:
            continue
        parent = result
        for k in keys[:-1]:
            parent = parent.get(k) if isinstance(parent, dict) else None
        if isinstance(parent, dict) and keys[-1] not in parent:
            out.append(f"{path}: missing" + (" (status ok)" if entry["required"] == "ok" else ""))
    return out
