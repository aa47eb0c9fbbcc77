"""Load a TOML model file into a :class:`rheolin.mechanics.Model`, validating it once:
read, parse (:mod:`rheolin.io.schema`), build (:mod:`rheolin.io.build`).

Every problem is reported as a :class:`rheolin.ModelError` whose lines start with the field
path (``shafts[1].bearings[0].stiffness``) and say what is allowed.
"""

from __future__ import annotations

import hashlib
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from ..errors import ModelError
from ..mechanics.model import Model
from .build import build_model
from .schema import ModelFile, field_path, table_class

__all__ = ["LoadedModel", "load_model", "parse_document", "parse_model", "read_model"]


@dataclass
class LoadedModel:
    """A validated model file: the Model, the parsed file and the SHA-256 of its bytes."""

    model: Model
    spec: ModelFile
    sha256: str
    path: str


def load_model(path: str | Path) -> Model:
    """Read and validate a model file; return the :class:`~rheolin.mechanics.Model`.

    >>> from rheolin.data import example_path
    >>> m = load_model(example_path("gearbox"))
    >>> sorted(m.bodies)
    ['input', 'intermediate', 'output']
    """
    return read_model(path).model


def read_model(path: str | Path) -> LoadedModel:
    """Like :func:`load_model`, also returning the parsed file and its hash."""
    p = Path(path)
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise ModelError(f"cannot read model file {str(p)!r}: {exc.strerror}") from None
    return parse_model(raw, str(p), base=p.parent)


def parse_model(
    raw: bytes | str, source: str = "<string>", base: str | Path | None = None
) -> LoadedModel:
    """Validate TOML text; see :func:`load_model`. Relative file paths in the model (condensed
    bodies) are taken from ``base`` (default: the working directory)."""
    data = raw.encode() if isinstance(raw, str) else raw
    try:
        doc = tomllib.loads(data.decode("utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ModelError(f"{source}: not valid TOML: {exc}") from None
    return parse_document(doc, source, base, sha256=hashlib.sha256(data).hexdigest())


def parse_document(
    doc: dict[str, Any],
    source: str = "<document>",
    base: str | Path | None = None,
    *,
    sha256: str = "",
) -> LoadedModel:
    """Validate a model file already read into a dict (``tomllib``), e.g. one whose values a
    parameter study changed; the same checks and messages as :func:`parse_model`.

    >>> import tomllib
    >>> from rheolin.data import example_text
    >>> doc = tomllib.loads(example_text("rotor"))
    >>> doc["shafts"][0]["bearings"][0]["stiffness"][0] = "6e7 N/m"
    >>> float(parse_document(doc).model.joints["drive_end"]["K"][0, 0])
    60000000.0
    """
    try:
        spec = ModelFile.model_validate(doc)
    except ValidationError as exc:
        raise ModelError(_format(exc, source)) from None
    model = build_model(spec, Path(base) if base is not None else Path.cwd())
    return LoadedModel(model, spec, sha256, source)


# ---------------------------------------------------------------------- error messages
def _path(loc: tuple[Any, ...]) -> str:
    return field_path(loc) or "<file>"


def _fields_at(loc: tuple[Any, ...]) -> list[str]:
    """The keys allowed at ``loc`` (for "unknown key" messages)."""
    cls: Any = ModelFile
    for part in loc:
        if isinstance(part, int):
            continue
        fields = getattr(cls, "model_fields", {})
        field = fields.get(part)
        if field is None:
            return []
        cls = table_class(field.annotation)
    return list(getattr(cls, "model_fields", {}))


def _format(exc: ValidationError, source: str) -> str:
    lines, seen = [], set()
    for err in exc.errors():
        loc = tuple(x for x in err["loc"] if not (isinstance(x, str) and "[" in x))
        path = _path(loc)
        kind, msg = err["type"], err["msg"].removeprefix("Value error, ")
        if kind == "extra_forbidden":
            msg = f"unknown key; allowed keys here: {', '.join(_fields_at(loc[:-1]))}"
        elif kind == "missing":
            msg = "required field is missing"
        if (path, msg) in seen:  # union members repeat the same complaint
            continue
        seen.add((path, msg))
        lines.append(f"{path}: {msg}")
    return f"{source}: invalid model file\n  " + "\n  ".join(lines)
