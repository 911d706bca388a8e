"""Bond graphs as JSON files: :func:`save`, :func:`load` and their dict forms.

The file format is documented in ``docs/json-schema.md`` and described by the
JSON Schema ``bondgraph/graph.schema.json``.  In short::

    {"format": "bondcosim-graph", "version": 1, "name": ..., "description": ...,
     "elements": [element.to_dict(), ...],
     "bonds": [{"name": ..., "tail": [element, port], "head": [element, port]}, ...],
     "inputs": [...], "parameters": [...], "outputs": [...], "operating_point": {...}}

Loading validates at the boundary and collects *every* problem, each with the
JSON path of the offending entry (``elements[3].params.c.value``), before
raising one :class:`~bondgraph.errors.SchemaError` whose ``problems`` lists
them all.  A file is accepted exactly when the building API
(:meth:`BondGraph.add`, :meth:`~BondGraph.connect`, ...) accepts what it
describes: expressions are parsed, and causality assigned, by
:meth:`BondGraph.equations`, as for a graph built in Python.

Saving writes keys in a fixed order (indented by 2, no key sorting, lists
of scalars on one line, UTF-8, ``\\n`` line ends), so that save -> load ->
save is byte-identical; it checks that the file it writes loads back.
"""
from __future__ import annotations

import copy
import difflib
import inspect
import json
import math
import os
from typing import Any

from .elements.base import ELEMENT_KINDS
from .errors import BondcosimError, SchemaError, UnknownElementKindError
from .graph import BondGraph
from .guards import guard_from_dict
from .json_form import FORMAT, VERSION, graph_to_dict
from .params import DOMAINS, Param

__all__ = ["ELEMENT_KEYS", "FORMAT", "VERSION", "dumps", "graph_from_dict", "graph_to_dict", "load", "save"]


# Type tags of values in the file (``map:<tag>`` is an object of name -> <tag>).
_WHAT = {
    "str": "a string",
    "id": "an identifier (letters, digits and _, not starting with a digit)",
    "num": "a finite number",
    "numid": "a finite number or a parameter's name (an identifier)",
    "pos": "a positive finite number",
    "expr": "an expression (a non-empty string) or a number",
    "domain": f"a domain name, one of {', '.join(map(repr, DOMAINS))}",
    "params": "an object of parameter name -> {\"value\", \"unit\", \"description\"}",
    "portlist": "a list of port names (identifiers)",
    "portdirs": "an object of port name -> \"in\" or \"out\"",
    "end": "[element, port], two strings (port \"\" for one-port elements and junctions)",
    "list": "a list",
    "guards": "an object of guard name -> {\"expression\", \"min\", \"max\", \"unit\", \"description\"}",
}

_SOURCE = {"value": "expr", "input": "id", "unit": "str", "domain": "domain", "description": "str"}
_MODULATED = {"expression": "expr", "params": "params", "unit": "str", "domain": "domain", "locals": "map:expr",
              "description": "str"}
_STORAGE = {"value": "num", "law": "expr", "params": "params", "state": "id", "initial": "num",
            "domain": "domain", "unit": "str", "description": "str"}
_FIELD = {"ports": "portlist", "laws": "map:expr", "energy": "expr", "params": "params", "initial": "map:num",
          "domain": "domain", "description": "str"}

#: Element kind -> {key: type tag} of the keys an element entry may hold besides ``kind`` and ``name``
#: (the element's constructor arguments; ``tests/test_io_json.py`` checks the two agree).
ELEMENT_KEYS: dict[str, dict[str, str]] = {
    "Se": _SOURCE, "Sf": _SOURCE,
    "MSe": _MODULATED, "MSf": _MODULATED,
    "I": _STORAGE, "C": {**_STORAGE, "stiffness": "num"},
    "R": {"value": "num", "effort": "expr", "flow": "expr", "params": "params", "domain": "domain",
          "unit": "str", "description": "str"},
    "TF": {"modulus": "num", "params": "params", "unit": "str", "description": "str"},
    "GY": {"modulus": "num", "params": "params", "unit": "str", "description": "str"},
    "MTF": {"modulus": "expr", "params": "params", "unit": "str", "description": "str"},
    "MGY": {"modulus": "expr", "params": "params", "unit": "str", "description": "str"},
    "0": {"description": "str"}, "1": {"description": "str"},
    "CField": _FIELD, "IField": _FIELD,
    "Eq": {"ports": "portdirs", "outputs": "map:expr", "states": "map:expr", "initial": "map:num",
           "units": "map:str", "held": "map:expr", "fixed_step": "pos", "params": "params",
           "descriptions": "map:str", "locals": "map:expr", "guards": "guards", "description": "str"},
    "PneumaticC": {"pressure": "id", "length": "expr", "volume": "expr", "force": "expr", "flow_index": "expr",
                   "volume_index": "expr", "gas_constant": "expr", "temperature": "expr", "heat": "map:expr",
                   "initial_pressure": "num", "initial_temperature": "num", "guards": "guards", "params": "params",
                   "description": "str"},
}

# Top-level key -> type tag (None: checked by _check_header), and the keys a file must have.
_TOP = {"format": None, "version": None, "name": "id", "description": "str", "elements": "list", "bonds": "list",
        "inputs": "list", "parameters": "list", "outputs": "list", "operating_point": "map:num",
        "guards": "guards"}
_TOP_REQUIRED = ["format", "version", "name", "elements", "bonds"]
_PARAM_KEYS = {"name": "id", "value": "num", "unit": "str", "description": "str", "min": "num", "max": "num"}
_GUARD_KEYS = {"expression": "expr", "min": "num", "max": "num", "unit": "str", "description": "str"}
_INPUT_KEYS = {"name": "id", "default": "num", "unit": "str", "description": "str", "delay_of": "id",
               "delay": "id", "before": "numid"}
_OUTPUT_KEYS = {"name": "id", "expression": "expr", "unit": "str", "description": "str"}
_BOND_KEYS = {"name": "id", "tail": "end", "head": "end"}


class _Problems:
    """Every problem found, as ``"<json path>: <message>"`` lines."""

    def __init__(self):
        self.items: list[tuple[str, str]] = []

    def add(self, path: str, message: str) -> None:
        self.items.append((path, message))

    def raise_if_any(self, source: str) -> None:
        if not self.items:
            return
        lines = [f"{p}: {m}" if p else m for p, m in self.items]
        n = len(lines)
        head = f"{source}: {n} problem{'s' if n != 1 else ''} in the graph file"
        error = SchemaError(head + ":\n  - " + "\n  - ".join(lines))
        error.path = self.items[0][0]
        error.problems = lines
        raise error


# -- writing (the dict form is :mod:`bondgraph.json_form`) ----------------------
def dumps(graph: BondGraph) -> str:
    """The text :func:`save` writes: :func:`graph_to_dict` as JSON, indented by 2, plus a newline.

    Keys keep the order of :func:`graph_to_dict` (no sorting); a list of
    scalars, such as a bond end ``["j", ""]``, is written on one line.

    Raises
    ------
    SchemaError
        When the graph holds something the file format cannot represent
        (e.g. a NaN source value), naming it by JSON path.
    """
    data = graph_to_dict(graph)
    graph_from_dict(data, source=f"graph {graph.name!r}")  # only ever write what load accepts
    try:
        return _encode(data, 0) + "\n"
    except (TypeError, ValueError) as exc:
        raise SchemaError(f"graph {graph.name!r} cannot be written as JSON: {exc}") from None


def _encode(value, depth: int) -> str:
    """``json.dumps(value, indent=2)``, except that a list of scalars stays on one line (``["F", ""]``)."""
    pad, inner = "  " * depth, "  " * (depth + 1)
    if isinstance(value, dict) and value:
        items = [f"{inner}{json.dumps(str(k), ensure_ascii=False)}: {_encode(v, depth + 1)}" for k, v in value.items()]
        return "{\n" + ",\n".join(items) + f"\n{pad}}}"
    if isinstance(value, list) and any(isinstance(v, (dict, list)) for v in value):
        return "[\n" + ",\n".join(inner + _encode(v, depth + 1) for v in value) + f"\n{pad}]"
    return json.dumps(value, ensure_ascii=False, allow_nan=False)


def save(graph: BondGraph, path) -> None:
    """Write `graph` to `path` as JSON (UTF-8, ``\\n`` line ends, stable key order).

    Parameters
    ----------
    graph : BondGraph
    path : str or os.PathLike
        Destination file, overwritten.

    Raises
    ------
    SchemaError
        As :func:`dumps`; nothing is written then.
    """
    text = dumps(graph)
    with open(path, "w", encoding="utf-8", newline="\n") as stream:
        stream.write(text)


# -- reading -------------------------------------------------------------------
def load(path) -> BondGraph:
    """Read a graph written by :func:`save` (or by hand, following ``docs/json-schema.md``).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    BondGraph

    Raises
    ------
    SchemaError
        The file is not UTF-8 JSON (the message gives line and column), or
        does not match the schema; ``problems`` lists every problem with its
        JSON path.
    FileNotFoundError
        No file at `path`.
    """
    source = os.fspath(path)
    with open(path, "rb") as stream:
        raw = stream.read()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise SchemaError(f"{source}: not UTF-8 text (byte {exc.start}: {exc.reason})") from None
    problems = _Problems()

    def pairs(items):  # json keeps the last of two equal keys silently: report it
        keys = [k for k, _ in items]
        for key in sorted({k for k in keys if keys.count(k) > 1}):
            problems.add("", f"key {key!r} appears twice in one object (keys: {', '.join(keys)}); "
                             "JSON would silently keep the last")
        return dict(items)

    try:
        data = json.loads(text, object_pairs_hook=pairs)
    except json.JSONDecodeError as exc:
        lines = text.splitlines()
        line = lines[exc.lineno - 1] if exc.lineno <= len(lines) else ""
        raise SchemaError(f"{source}: not valid JSON: {exc.msg} at line {exc.lineno}, column {exc.colno}\n"
                          f"    {line}\n    {' ' * (exc.colno - 1)}^") from None
    return _from_dict(data, source, problems)


def graph_from_dict(data: Any, *, source: str = "graph data") -> BondGraph:
    """Build a :class:`BondGraph` from its dict form (what :func:`graph_to_dict` returns).

    Parameters
    ----------
    data : dict
        Parsed JSON.
    source : str
        Where `data` came from (a file name), for the error message.

    Returns
    -------
    BondGraph

    Raises
    ------
    SchemaError
        Listing every problem with its JSON path (``problems`` attribute).
    """
    return _from_dict(data, source, _Problems())


def _from_dict(data, source: str, problems: _Problems) -> BondGraph:
    if not isinstance(data, dict):
        problems.add("", f"expected a JSON object with keys {', '.join(_TOP)}, got {_show(data)}")
        problems.raise_if_any(source)
    if not _check_header(data, problems):  # a foreign file or another version: read by the wrong rules
        problems.raise_if_any(source)
    _check_object(data, "", _TOP, problems, what="a graph file", required=_TOP_REQUIRED)
    name, description = data.get("name"), data.get("description", "")
    graph = BondGraph(name if _is("id", name) else "model", description=description if _is("str", description) else "")
    broken = _add_elements(graph, _list(data, "elements"), problems)
    _add_bonds(graph, _list(data, "bonds"), broken, problems)
    _add_declarations(graph, data, problems)
    if _is("map:num", data.get("operating_point")):
        graph.operating_point.update(data["operating_point"])
    if isinstance(data.get("guards"), dict):
        for key, entry in data["guards"].items():
            try:
                graph.add_guard(guard_from_dict(key, entry))
            except (BondcosimError, KeyError, TypeError) as exc:
                problems.add(f"guards.{key}", str(exc))
    problems.raise_if_any(source)
    return graph


def _check_header(data: dict, problems: _Problems) -> bool:
    """Check ``format`` and ``version``; False when the rest of the file should not be read."""
    n_before = len(problems.items)
    if "format" in data and data["format"] != FORMAT:
        problems.add("format", f"expected {FORMAT!r}, got {_show(data['format'])}: not a bondcosim graph file")
    version = data.get("version", VERSION)
    if isinstance(version, bool) or not isinstance(version, int):
        problems.add("version", f"expected an integer format version ({VERSION}), got {_show(version)}")
    elif version != VERSION:
        problems.add("version", f"format version {version} is not supported; this bondcosim reads version {VERSION}")
    return len(problems.items) == n_before


def _list(data: dict, key: str) -> list:
    value = data.get(key)
    return value if isinstance(value, list) else []  # a non-list is reported by _check_object


def _add_elements(graph: BondGraph, entries: list, problems: _Problems) -> set[str]:
    """Add every valid element; return the names of entries that could not be built."""
    broken: set[str] = set()
    first: dict[str, int] = {}
    for i, entry in enumerate(entries):
        path = f"elements[{i}]"
        name = entry.get("name") if isinstance(entry, dict) else None
        if isinstance(name, str) and name in first:
            problems.add(f"{path}.name", f"duplicate element name {name!r}: elements[{first[name]}] has it too")
            continue
        if isinstance(name, str):
            first[name] = i
        element = _element(entry, path, problems)
        if element is None:
            broken.add(str(name))
        else:
            graph.add(element)
    return broken


def _element(entry, path: str, problems: _Problems):
    """The element `entry` describes, or None after recording why not."""
    kinds = ", ".join(sorted(ELEMENT_KINDS))
    if not isinstance(entry, dict) or not isinstance(entry.get("kind"), str):
        _check_object(entry, path, {"kind": None, "name": "id"}, problems, what="an element", required=["kind", "name"])
        if isinstance(entry, dict) and "kind" in entry:
            problems.add(f"{path}.kind", f"expected an element kind (a string), one of {kinds}; "
                                         f"got {_show(entry['kind'])}")
        return None
    kind, name = entry["kind"], entry.get("name")
    cls = ELEMENT_KINDS.get(kind)
    if cls is None:
        problems.add(f"{path}.kind", str(UnknownElementKindError(kind, list(ELEMENT_KINDS))))
        _check_object(entry, path, {"name": "id"}, problems, what="an element", required=["name"], extra=True)
        return None
    allowed, required = _constructor_keys(cls)
    keys = {"kind": None, "name": "id", **{k: ELEMENT_KEYS.get(kind, {}).get(k) for k in allowed}}
    if not _check_object(entry, path, keys, problems, what=f"{kind} element {name!r}", required=["name"] + required,
                         owner=f"{kind} {name!r}"):
        return None
    try:
        # a copy: some elements keep the mappings they are given, and the caller still owns `entry`
        return cls(name, **copy.deepcopy({k: v for k, v in entry.items() if k not in ("kind", "name")}))
    except (BondcosimError, TypeError, ValueError) as exc:
        problems.add(path, str(exc))
        return None


def _constructor_keys(cls) -> tuple[list[str], list[str]]:
    """(allowed, required) keyword names of an element class's constructor, besides ``name``."""
    allowed, required = [], []
    for p in list(inspect.signature(cls).parameters.values())[1:]:
        if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
            allowed.append(p.name)
            if p.default is p.empty:
                required.append(p.name)
    return allowed, required


def _add_bonds(graph: BondGraph, entries: list, broken: set[str], problems: _Problems) -> None:
    for i, entry in enumerate(entries):
        path = f"bonds[{i}]"
        if not _check_object(entry, path, _BOND_KEYS, problems, what="a bond", required=list(_BOND_KEYS)):
            continue
        ends = {"tail": entry["tail"], "head": entry["head"]}
        if any(element in broken for element, _ in ends.values()):
            continue  # that element's own problems are reported already
        n_before = len(problems.items)
        for end, (element, port) in ends.items():
            _check_end(graph, element, port, f"{path}.{end}", problems)
        if len(problems.items) > n_before:
            continue
        try:
            graph.connect(tuple(entry["tail"]), tuple(entry["head"]), name=entry["name"])
        except BondcosimError as exc:
            problems.add(path, str(exc))


def _check_end(graph: BondGraph, element: str, port: str, path: str, problems: _Problems) -> None:
    target = graph.elements.get(element)
    if target is None:
        problems.add(path, f"no element named {element!r}; elements are {', '.join(graph.elements) or '(none)'}")
    elif target.ports is None and port != "":
        problems.add(path, f"junction {element!r} ({target.kind}) has no named ports; write [{element!r}, \"\"], "
                           f"got port {port!r}")
    elif target.ports is not None and port not in target.ports:
        known = ("its only port is \"\" (a one-port element)" if target.ports == ("",)
                 else f"its ports are {', '.join(map(repr, target.ports))}")
        problems.add(path, f"{target.kind} {element!r} has no port {port!r}; {known}")


def _add_declarations(graph: BondGraph, data: dict, problems: _Problems) -> None:
    """Graph-wide parameters, inputs and outputs."""
    specs = {"parameters": (_PARAM_KEYS, ["name", "value"]), "inputs": (_INPUT_KEYS, ["name"]),
             "outputs": (_OUTPUT_KEYS, ["name", "expression"])}
    for key, (keys, required) in specs.items():
        seen: dict[str, int] = {}
        for i, entry in enumerate(_list(data, key)):
            path, name = f"{key}[{i}]", entry.get("name") if isinstance(entry, dict) else None
            ok = _check_object(entry, path, keys, problems, what=f"an entry of {key}", required=required,
                               owner=f"{key[:-1]} {name!r}" if key == "parameters" else "")
            if isinstance(name, str) and name in seen:
                problems.add(f"{path}.name", f"duplicate {key[:-1]} name {name!r}: {key}[{seen[name]}] has it too")
                continue
            seen.setdefault(name, i)
            if not ok:
                continue
            rest = {k: v for k, v in entry.items() if k != "name"}
            try:
                if key == "parameters":
                    graph.add_parameter(Param(name, **rest))
                elif key == "inputs":
                    graph.add_input(name, **rest)
                else:
                    graph.add_output(name, **rest)
            except BondcosimError as exc:
                problems.add(path, str(exc))


# -- value checks ------------------------------------------------------------------
def _check_object(entry, path: str, keys: dict, problems: _Problems, *, what: str, required,
                  owner: str = "", extra: bool = False) -> bool:
    """Record every problem of `entry` as an object with `keys` (key -> type tag or None), the
    `required` ones among them; True when there is none.  `extra` allows keys not in `keys`."""
    if not isinstance(entry, dict):
        problems.add(path, f"expected {what}: an object with keys {', '.join(keys)}; got {_show(entry)}")
        return False
    n_before = len(problems.items)
    prefix = f"{path}." if path else ""
    for key in required:
        if key not in entry:
            problems.add(path, f"missing key {key!r} (required in {what})")
    for key, value in entry.items():
        if key not in keys and not extra:
            close = difflib.get_close_matches(str(key), list(keys), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            problems.add(f"{prefix}{key}", f"unknown key {key!r} in {what}{hint}; expected keys are {', '.join(keys)}")
        elif keys.get(key) is not None:
            _check_value(keys[key], value, f"{prefix}{key}", problems, owner=owner)
    return len(problems.items) == n_before


def _check_value(tag: str, value, path: str, problems: _Problems, *, owner: str = "") -> None:
    """Record a problem when `value` is not of type `tag` (recursing into containers)."""
    if tag == "params" and isinstance(value, dict):
        for name, entry in value.items():
            where = f"{path}.{name}"
            if not _is("id", name):
                problems.add(where, f"parameter name {name!r} is not {_WHAT['id']}")
            ok = _check_object(entry, where, _PARAM_KEYS, problems, what=f"parameter {name!r}", required=["value"],
                               owner=f"parameter {name!r}" + (f" of {owner}" if owner else ""))
            if ok and entry.get("name", name) != name:
                problems.add(f"{where}.name", f"parameter {name!r} says its name is {entry['name']!r}")
    elif tag == "guards" and isinstance(value, dict):
        for name, entry in value.items():
            where = f"{path}.{name}"
            if not _is("id", name):
                problems.add(where, f"guard name {name!r} is not {_WHAT['id']}")
            _check_object(entry, where, _GUARD_KEYS, problems, what=f"guard {name!r}",
                          required=["expression"], owner=f"guard {name!r}" + (f" of {owner}" if owner else ""))
    elif tag.startswith("map:") and isinstance(value, dict):
        for key, item in value.items():
            _check_value(tag[4:], item, f"{path}.{key}", problems, owner=owner)
    elif not _is(tag, value):
        what = f"an object of name -> {_WHAT[tag[4:]]}" if tag.startswith("map:") else _WHAT[tag]
        problems.add(path, f"{owner + ': ' if owner else ''}expected {what}, got {_show(value)}")


def _is(tag: str, value) -> bool:
    """True when `value` is of the type `tag` names."""
    if tag.startswith("map:"):
        return isinstance(value, dict) and all(_is(tag[4:], v) for v in value.values())
    if tag == "str":
        return isinstance(value, str)
    if tag == "id":
        return isinstance(value, str) and value.isidentifier()
    if tag == "num":
        return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if tag == "numid":
        return _is("num", value) or _is("id", value)
    if tag == "pos":
        return _is("num", value) and value > 0
    if tag == "expr":
        return (isinstance(value, str) and bool(value.strip())) or _is("num", value)
    if tag == "domain":
        return isinstance(value, str) and value in DOMAINS
    if tag in ("list", "params", "guards"):  # params/guards entries are checked by _check_value
        return isinstance(value, list if tag == "list" else dict)
    if tag == "portlist":
        return isinstance(value, list) and all(_is("id", p) for p in value)
    if tag == "portdirs":
        return isinstance(value, dict) and all(_is("id", p) and d in ("in", "out") for p, d in value.items())
    if tag == "end":
        return isinstance(value, list) and len(value) == 2 and all(isinstance(v, str) for v in value)
    raise AssertionError(f"unknown type tag {tag!r}")  # pragma: no cover - tags are this module's own


def _show(value) -> str:
    """A short JSON rendering of `value` with its JSON type, for messages."""
    kinds = {dict: "an object", list: "a list", str: "a string", bool: "a boolean", type(None): "null"}
    kind = kinds.get(type(value), "a number" if isinstance(value, (int, float)) else type(value).__name__)
    try:
        text = json.dumps(value, ensure_ascii=False)
    except (TypeError, ValueError):
        text = repr(value)
    text = text if len(text) <= 60 else text[:57] + "..."
    return text if kind == "null" else f"{text} ({kind})"
