"""Study parameters: a path into the model file and the values it takes (``--vary``).

A path follows the TOML structure of the model file (``docs/model-format.md``,
:mod:`rheolin.io.schema`), with dots between keys:

* an item of an array of tables is chosen by its ``name`` (``meshes.stage1``) or by its
  index (``shafts[0]``);
* ``bearings.NAME`` is the bearing ``NAME`` wherever it sits (bearings are written under
  their body: ``[[shafts.bearings]]``, ``[[shafts.rolling_bearings]]``), ``bodies.NAME``
  the shaft, rigid or condensed body;
* indices after the last key pick one entry of a list value (``stiffness[0][1]``,
  ``model.gravity[1]``); without them the value replaces the key's whole value, exactly as
  if it were written in the file (``bearings.input_A.stiffness = "2e8 N/m"`` makes that
  bearing isotropic in its translational components).

Values: ``start:stop:count unit`` (``count`` values from ``start`` to ``stop``, both
included) or a list ``v1,v2,... unit``. Each value is written into the file's data and the
model is validated as a model file, so a wrong unit or a value out of range is reported with
the field that holds it.

>>> import tomllib
>>> from rheolin.data import example_text
>>> doc = tomllib.loads(example_text("gearbox"))
>>> p = parse_vary("bearings.input_A.stiffness=1e8:4e8:7 N/m", doc)
>>> p.field, p.unit, p.values[:3]
('shafts[0].bearings[0].stiffness', 'N/m', (100000000.0, 150000000.0, 200000000.0))
>>> apply(doc, [(p, 1)])["shafts"][0]["bearings"][0]["stiffness"]
'150000000.0 N/m'
"""

from __future__ import annotations

import copy
import math
import re
import typing
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ModelError
from ..io.schema import ModelFile, field_path, table_class

__all__ = ["Parameter", "ParameterError", "apply", "parameter", "parse_vary"]

_BODIES = ("shafts", "rigid_bodies", "condensed_bodies")
_SEGMENT = re.compile(r"^([^\[\].\s]+)((?:\[\d+\])*)$")
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_RANGE = re.compile(rf"^\s*({_NUMBER})\s*:\s*({_NUMBER})\s*:\s*(\S+?)\s*([A-Za-z].*)?$")
_ITEM = re.compile(rf"^\s*({_NUMBER})\s*(.*?)\s*$")


class ParameterError(ModelError):
    """A parameter path or its values are wrong; the message starts with the path."""


@dataclass(frozen=True)
class Parameter:
    """One varied model parameter.

    Attributes
    ----------
    path
        The path as written (``bearings.input_A.stiffness``); the study's dimension name.
    location
        Keys and indices of the value in the file's data.
    field
        The field as the model-file validation names it (``shafts[0].bearings[0].stiffness``).
    values
        The values, in ``unit``.
    unit
        The unit the values are given in (pint syntax); ``""``: plain numbers, SI.
    integer
        The values are whole numbers written without a unit (tooth counts, orders).
    """

    path: str
    location: tuple[str | int, ...]
    field: str
    values: tuple[float, ...]
    unit: str = ""
    integer: bool = False

    def entry(self, i: int) -> Any:
        """Value ``i`` as written into the model file's data."""
        v = self.values[i]
        if self.integer:
            return int(v)
        return f"{v!r} {self.unit}" if self.unit else float(v)

    def describe(self, i: int) -> str:
        """``"bearings.input_A.stiffness = 1.5e+08 N/m"``."""
        return f"{self.path} = {self.values[i]:.6g}{' ' + self.unit if self.unit else ''}"


def parse_vary(text: str, doc: dict[str, Any]) -> Parameter:
    """``"path=values"`` (the ``--vary`` option) against the model file's data ``doc``."""
    path, sep, values = text.partition("=")
    if not sep or not path.strip():
        raise ParameterError(
            f"{text.strip()!r}: write PATH=VALUES, e.g. 'meshes.stage1.damping=0:2e3:5'"
        )
    return parameter(path.strip(), values, doc)


def parameter(path: str, values: str | Sequence[Any], doc: dict[str, Any]) -> Parameter:
    """A :class:`Parameter` from a path and values (a string as for ``--vary``, or a sequence
    of numbers or quantity strings in one unit).

    Raises
    ------
    ModelError
        One line naming the path: unknown key or name, a value that is not a number, a range
        that is empty or backwards, repeated values. Units are checked by the model file's
        validation (:func:`rheolin.study.spec.StudySpec.create`).
    """
    location, field = _resolve(path, doc)
    if location[:2] == ("model", "speed"):
        raise ParameterError(f"{path}: the input speed is the study's speed axis (--speeds)")
    try:
        numbers, unit, integer = _values(values)
    except ValueError as exc:
        raise ParameterError(f"{path}: {exc}") from None
    if len(set(numbers)) != len(numbers):
        raise ParameterError(f"{path}: values repeat ({_show(numbers, unit)})")
    return Parameter(path, location, field, tuple(numbers), unit, integer)


def apply(doc: dict[str, Any], assignments: Sequence[tuple[Parameter, int]]) -> dict[str, Any]:
    """A copy of ``doc`` with value ``i`` of each parameter written into it."""
    out = copy.deepcopy(doc)
    for p, i in assignments:
        node: Any = out
        for key in p.location[:-1]:
            if isinstance(key, str) and key not in node:
                node[key] = {}  # a table the file leaves at its defaults ([harmonics])
            node = node[key]
        node[p.location[-1]] = p.entry(i)
    return out


# ---------------------------------------------------------------------- values
def _values(spec: str | Sequence[Any]) -> tuple[list[float], str, bool]:
    if not isinstance(spec, str):
        items = list(spec)
        if not items:
            raise ValueError("no values given")
        texts = [x if isinstance(x, str) else repr(x) for x in items]
        return _list(texts)
    text = spec.strip()
    if not text:
        raise ValueError("no values given; write start:stop:count unit or v1,v2,... unit")
    m = _RANGE.match(text)
    if m:
        return _range(m.group(1), m.group(2), m.group(3), (m.group(4) or "").strip())
    if ":" in text:
        raise ValueError(f"cannot read the range {text!r}; write start:stop:count unit")
    return _list([t for t in text.split(",")])


def _range(first: str, last: str, count_text: str, unit: str) -> tuple[list[float], str, bool]:
    start, stop = float(first), float(last)
    if not (math.isfinite(start) and math.isfinite(stop)):
        raise ValueError("the range must be finite")
    if not re.fullmatch(r"\d+", count_text):
        raise ValueError(
            f"the count in start:stop:count must be a whole number, got {count_text!r}"
        )
    count = int(count_text)
    if count == 0:
        raise ValueError(f"the range {first}:{last}:0 is empty (count 0)")
    if stop < start:
        raise ValueError(f"the range {first}:{last}:{count} is backwards (stop < start)")
    if count == 1 and stop != start:
        raise ValueError("a range of one value needs start == stop; or give a list")
    if count > 1 and stop == start:
        raise ValueError(f"the range {first}:{last}:{count} is empty (start == stop)")
    values = np.linspace(start, stop, count).tolist()
    ints = not unit and all(_is_int(t) for t in (first, last))
    ints = ints and all(float(v).is_integer() for v in values)
    return [float(v) for v in values], unit, ints


def _list(texts: list[str]) -> tuple[list[float], str, bool]:
    numbers, units = [], []
    for t in texts:
        m = _ITEM.match(t)
        if not m:
            raise ValueError(f"cannot read {t.strip()!r} as a number with an optional unit")
        numbers.append(float(m.group(1)))
        units.append(m.group(2))
    if not numbers or not all(math.isfinite(v) for v in numbers):
        raise ValueError("values must be finite numbers")
    given = {u for u in units if u}
    if len(given) > 1:
        raise ValueError(f"give the values in one unit, got {sorted(given)}")
    unit = given.pop() if given else ""
    if unit and units[-1] != unit:  # "1e8 N/m, 2e8": a unit on some items only
        raise ValueError("write the unit once at the end or after every value")
    ints = not unit and all(_is_int(_ITEM.match(t).group(1)) for t in texts)  # type: ignore[union-attr]
    return numbers, unit, ints


def _is_int(text: str) -> bool:
    return re.fullmatch(r"[-+]?\d+", text.strip()) is not None


def _show(values: Sequence[float], unit: str) -> str:
    return ", ".join(f"{v:g}" for v in values) + (f" {unit}" if unit else "")


# ---------------------------------------------------------------------- paths
def _resolve(path: str, doc: dict[str, Any]) -> tuple[tuple[str | int, ...], str]:
    """Keys and indices of ``path`` in ``doc``, and the field name the loader uses."""
    segments = path.split(".")
    parsed = []
    for s in segments:
        m = _SEGMENT.match(s)
        if not m:
            raise ParameterError(
                f"{path}: cannot read {s!r}; write keys with dots, e.g. shafts.input"
            )
        parsed.append((m.group(1), [int(i) for i in re.findall(r"\d+", m.group(2))]))
    location: list[str | int] = []
    node: Any = doc
    cls: Any = ModelFile
    i = 0
    head = parsed[0][0]
    if head in ("bearings", "bodies") and not parsed[0][1]:
        if len(parsed) < 3:
            raise ParameterError(f"{path}: write {head}.NAME.key")
        location, cls = _named(path, head, parsed[1][0], parsed[1][1], doc)
        node = doc
        for key in location:
            node = node[key]
        i = 2
    while i < len(parsed):
        key, indices = parsed[i]
        fields = getattr(cls, "model_fields", {})
        if key not in fields:
            raise ParameterError(
                f"{path}: unknown key {key!r} at {field_path(location) or 'the top level'}; "
                f"allowed keys here: {', '.join(fields)}"
            )
        item_cls = table_class(fields[key].annotation)
        is_array = item_cls is not None and _is_list(fields[key].annotation)
        last = i == len(parsed) - 1
        if item_cls is None or (last and not is_array and not indices):
            if not last:
                raise ParameterError(f"{path}: {field_path([*location, key])} has no keys inside")
            location.append(key)
            node = node.get(key) if isinstance(node, dict) else None
            for n in indices:
                if not isinstance(node, list) or not 0 <= n < len(node):
                    raise ParameterError(
                        f"{path}: {field_path(location)} has no entry [{n}] in the file "
                        "(index into a list value, or vary the whole value)"
                    )
                location.append(n)
                node = node[n]
            return tuple(location), field_path(location)
        location.append(key)
        if not is_array:  # a table ([harmonics], [shafts.section])
            if indices:
                raise ParameterError(f"{path}: {field_path(location)} is a table, not a list")
            node = node.get(key, {}) if isinstance(node, dict) else {}
            cls = item_cls
            i += 1
            continue
        items = node.get(key, []) if isinstance(node, dict) else []
        if indices:
            if len(indices) > 1 or not 0 <= indices[0] < len(items):
                raise ParameterError(f"{path}: {field_path(location)} has {len(items)} entries")
            location.append(indices[0])
            node = items[indices[0]]
            i += 1
        else:
            if last:
                raise ParameterError(
                    f"{path}: name an entry of {field_path(location)} and a key in it"
                )
            name = parsed[i + 1][0]
            if parsed[i + 1][1]:
                raise ParameterError(f"{path}: write {key}.NAME or {key}[INDEX]")
            j = _by_name(path, items, name, field_path(location))
            location.append(j)
            node = items[j]
            i += 2
        cls = item_cls
    raise ParameterError(f"{path}: ends at {field_path(location)}; name a value (a key) inside it")


def _named(
    path: str, kind: str, name: str, indices: list[int], doc: dict[str, Any]
) -> tuple[list[str | int], Any]:
    """Location and schema class of the bearing or body called ``name``."""
    from ..io.schema import Bearing, RollingBearing, Shaft

    if indices:
        raise ParameterError(f"{path}: {kind}.NAME takes a name, not an index")
    found: list[tuple[list[str | int], Any]] = []
    names = []
    for table in _BODIES:
        for b, body in enumerate(doc.get(table, [])):
            if kind == "bodies":
                names.append(str(body.get("name")))
                if body.get("name") == name:
                    cls = table_class(ModelFile.model_fields[table].annotation) or Shaft
                    found.append(([table, b], cls))
                continue
            for key, cls in (("bearings", Bearing), ("rolling_bearings", RollingBearing)):
                for j, bearing in enumerate(body.get(key, [])):
                    names.append(str(bearing.get("name")))
                    if bearing.get("name") == name:
                        found.append(([table, b, key, j], cls))
    what = "bearing" if kind == "bearings" else "body"
    if not found:
        raise ParameterError(f"{path}: no {what} named {name!r}; {kind}: {', '.join(names)}")
    if len(found) > 1:
        raise ParameterError(f"{path}: {len(found)} {kind} are named {name!r}")
    return found[0]


def _by_name(path: str, items: list[Any], name: str, where: str) -> int:
    hits = [j for j, it in enumerate(items) if isinstance(it, dict) and it.get("name") == name]
    if len(hits) != 1:
        names = [str(it.get("name")) for it in items if isinstance(it, dict)]
        if not hits:
            raise ParameterError(f"{path}: no entry of {where} named {name!r}; names: {names}")
        raise ParameterError(f"{path}: {len(hits)} entries of {where} are named {name!r}")
    return hits[0]


def _is_list(annotation: Any) -> bool:
    if typing.get_origin(annotation) is list:
        return True
    return any(_is_list(a) for a in typing.get_args(annotation))
