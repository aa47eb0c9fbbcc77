"""What a study computes: the model file, the speeds, the varied parameters, the settings.

Its :attr:`StudySpec.key` (SHA-256 of :meth:`StudySpec.identity`) names the checkpoint: the
model file's hash (and those of the matrix files it reads), every speed, every parameter value
and every setting that changes a point's result. Two runs with the same key compute the same
points, so a re-run reuses finished ones; anything else is a different study.

>>> import numpy as np
>>> from rheolin.data import example_path
>>> spec = StudySpec.create(example_path("rotor"), [300.0, 400.0],
...                         {"bearings.free_end.damping": "500,800 N*s/m"})
>>> spec.shape, spec.n_points, spec.dims
((2, 2), 4, ('bearings.free_end.damping', 'speed'))
>>> spec.combo_of(3), float(spec.speeds[spec.speed_of(3)])
(1, 400.0)
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..errors import ModelError
from ..io.loader import LoadedModel, parse_document
from .params import Parameter, ParameterError, apply, parameter, parse_vary

__all__ = ["FORMAT", "Settings", "StudySpec"]

#: Version of the checkpoint layout and of the identity below (2: continuation blocks; 3:
#: blocks of 16 speeds, off-centre Floquet exponents tracked).
FORMAT = 3

#: Most consecutive speeds solved as one sequence (:attr:`StudySpec.block`): the first speed
#: of a block is solved cold, so longer blocks start cold less often, while a 1000-speed
#: run-up still splits into enough blocks to spread over the workers of a local machine.
CONTINUATION_BLOCK = 16


@dataclass(frozen=True)
class Settings:
    """Per-point settings (see :func:`rheolin.results.solve_point`).

    ``order``/``max_order`` None: the model file's ``[harmonics]`` (of each grid point).
    ``stability``: the per-point verdict (None: when it fits the memory budget, True, False).
    ``stability_map``: keep every point's Floquet result and build the stability map of each
    parameter combination (also when the per-point verdict is off).
    ``floquet_rtol``: the relative accuracy of each verdict's largest real part
    (:func:`rheolin.floquet`'s ``rtol``; None: its default).
    """

    method: str = "auto"
    order: int | None = None
    max_order: float | None = None
    rtol: float = 1e-10
    stability: bool | None = None
    stability_map: bool = True
    floquet_rtol: float | None = None


@dataclass(frozen=True, eq=False)
class StudySpec:
    """A study: the grid of parameter values times the speeds.

    Points are numbered combination-major: point ``i`` is speed ``i % n_speeds`` of parameter
    combination ``i // n_speeds`` (combinations in C order over :attr:`parameters`).

    Consecutive speeds of a combination form blocks of :attr:`block` points, solved in order
    by one task: each point after the first starts from its predecessor's solution and
    Floquet eigenvectors (continuation). The blocks depend on the speeds only, so every
    point's result is the same whatever the workers, the chunks and the interruptions.
    """

    document: dict[str, Any]
    model_sha256: str
    source: str
    base: str
    speeds: np.ndarray
    parameters: tuple[Parameter, ...] = ()
    settings: Settings = field(default_factory=Settings)
    files: tuple[tuple[str, str], ...] = ()

    @classmethod
    def create(
        cls,
        model: str | Path,
        speeds: Sequence[float] | np.ndarray,
        vary: Mapping[str, str | Sequence[Any]] | Sequence[str] = (),
        settings: Settings | None = None,
    ) -> StudySpec:
        """Read and validate the model file, the speeds [rad/s] and the parameters.

        ``vary`` maps parameter paths to values (``{"bearings.input_A.stiffness":
        "1e8:4e8:7 N/m"}``) or lists ``"path=values"`` strings. Every value of every parameter
        is written into the file's data and validated as a model file, and must keep the
        speed ratios (the harmonic numbering) of the model.

        Raises
        ------
        ModelError
            Naming the field (one line for a parameter).
        """
        path = Path(model)
        try:
            raw = path.read_bytes()
        except OSError as exc:
            raise ModelError(f"cannot read model file {str(path)!r}: {exc.strerror}") from None
        try:
            doc = tomllib.loads(raw.decode("utf-8"))
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
            raise ModelError(f"{path}: not valid TOML: {exc}") from None
        base_model = parse_document(doc, str(path), path.parent).model
        w = np.asarray(speeds, dtype=float).ravel()
        if w.size == 0 or not np.all(np.isfinite(w)) or np.any(w <= 0):
            raise ModelError("speeds: give one or more speeds > 0 [rad/s]")
        if np.unique(w).size != w.size:
            raise ModelError("speeds: a speed is repeated")
        if isinstance(vary, Mapping):
            params = tuple(parameter(k, v, doc) for k, v in vary.items())
        else:
            params = tuple(parse_vary(t, doc) for t in vary)
        seen: dict[str, str] = {}
        for p in params:
            for earlier, other in seen.items():  # the same value, or a value inside another
                if p.field == earlier or any(
                    a.startswith(b) and a[len(b)] in "[."
                    for a, b in ((p.field, earlier), (earlier, p.field))
                    if len(a) > len(b)
                ):
                    raise ParameterError(
                        f"{p.path}: {p.field} is already varied (as {other}: {earlier}); vary a "
                        "value or a part of it, not both"
                    )
            seen[p.field] = p.path
        ratio = base_model.speed_plan().base
        for p in params:
            for i in range(len(p.values)):
                check = _validate(doc, path, p, i)
                if check.model.speed_plan().base != ratio:
                    raise ParameterError(
                        f"{p.path}: {p.describe(i)} changes the speed ratios (w1 = "
                        f"{check.model.speed_plan().base} instead of {ratio} x input speed); "
                        "a study keeps the model's harmonic numbering: study it separately"
                    )
        return cls(
            document=doc,
            model_sha256=hashlib.sha256(raw).hexdigest(),
            source=str(path),
            base=str(path.resolve().parent),
            speeds=np.sort(w),
            parameters=params,
            settings=settings or Settings(),
            files=_file_hashes(doc, path.parent),
        )

    # ------------------------------------------------------------------ the grid
    @property
    def dims(self) -> tuple[str, ...]:
        """Dimension names: the parameter paths, then ``speed``."""
        return (*(p.path for p in self.parameters), "speed")

    @property
    def grid(self) -> tuple[int, ...]:
        """Number of values per parameter."""
        return tuple(len(p.values) for p in self.parameters)

    @property
    def shape(self) -> tuple[int, ...]:
        """``(*grid, n_speeds)``."""
        return (*self.grid, self.speeds.size)

    @property
    def n_combos(self) -> int:
        """Number of parameter combinations (1 without parameters)."""
        return int(np.prod(self.grid, dtype=int))

    @property
    def n_points(self) -> int:
        """Combinations times speeds."""
        return self.n_combos * self.speeds.size

    def combo_of(self, point: int) -> int:
        """The parameter combination of a point."""
        return point // self.speeds.size

    def speed_of(self, point: int) -> int:
        """The speed index of a point."""
        return point % self.speeds.size

    @property
    def block(self) -> int:
        """Speeds per continuation block: up to :data:`CONTINUATION_BLOCK`, fewer for short
        sweeps (at least 16 blocks per combination, so that they spread over the workers).

        >>> import numpy as np
        >>> from rheolin.data import example_path
        >>> [StudySpec.create(example_path("rotor"), np.arange(1.0, n + 1)).block
        ...  for n in (7, 40, 1000)]
        [1, 2, 16]
        """
        return max(1, min(CONTINUATION_BLOCK, self.speeds.size // 16))

    def block_of(self, point: int) -> tuple[int, int]:
        """``(combination, block)`` of a point."""
        return self.combo_of(point), self.speed_of(point) // self.block

    def assignments(self, combo: int) -> list[tuple[Parameter, int]]:
        """``(parameter, value index)`` of a combination."""
        idx = np.unravel_index(combo, self.grid) if self.parameters else ()
        return [(p, int(i)) for p, i in zip(self.parameters, idx, strict=True)]

    def describe(self, combo: int) -> str:
        """``"bearings.free_end.damping = 800 N*s/m"`` (empty without parameters)."""
        return ", ".join(p.describe(i) for p, i in self.assignments(combo))

    def loaded(self, combo: int) -> LoadedModel:
        """The model file with the combination's values, validated."""
        doc = apply(self.document, self.assignments(combo))
        return parse_document(doc, self.source, self.base, sha256=self.model_sha256)

    # ------------------------------------------------------------------ identity
    def identity(self) -> dict[str, Any]:
        """Everything that decides the points' results, as plain JSON data."""
        return {
            "format": FORMAT,
            "rheolin": __version__,
            "model_sha256": self.model_sha256,
            "files": [list(f) for f in self.files],
            "speeds": [float(w).hex() for w in self.speeds],
            "parameters": [
                {
                    "path": p.path,
                    "field": p.field,
                    "values": [float(v).hex() for v in p.values],
                    "unit": p.unit,
                    "integer": p.integer,
                }
                for p in self.parameters
            ],
            "settings": dataclasses.asdict(self.settings),
        }

    @functools.cached_property
    def key(self) -> str:
        """SHA-256 of :meth:`identity`."""
        text = json.dumps(self.identity(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()

    def difference(self, other: Mapping[str, Any]) -> str:
        """What differs from another study's identity, in words (``""`` if nothing)."""
        mine = self.identity()
        if other.get("format") != mine["format"]:
            return "it was written by a different version of the checkpoint format"
        if other.get("model_sha256") != mine["model_sha256"]:
            old, new = str(other.get("model_sha256"))[:12], mine["model_sha256"][:12]
            return f"the model file changed (SHA-256 {old}... -> {new}...)"
        if other.get("files") != mine["files"]:
            return "a matrix file the model reads changed"
        if other.get("speeds") != mine["speeds"]:
            n = len(other.get("speeds") or [])
            return f"the speeds differ ({n} then, {self.speeds.size} now)"
        if other.get("parameters") != mine["parameters"]:
            return "the varied parameters or their values differ"
        theirs = other.get("settings", {})
        for k, v in mine["settings"].items():
            if theirs.get(k) != v:
                return f"the setting {k} differs ({theirs.get(k)!r} then, {v!r} now)"
        if other.get("rheolin") != mine["rheolin"]:
            return f"it was computed by rheolin {other.get('rheolin')} (now {__version__})"
        return ""


def _validate(doc: dict[str, Any], path: Path, p: Parameter, i: int) -> LoadedModel:
    """The model with value ``i`` of ``p``; a one-line ModelError naming the field if not."""
    try:
        return parse_document(apply(doc, [(p, i)]), str(path), path.parent)
    except ModelError as exc:
        lines = [ln.strip() for ln in str(exc).splitlines()]
        lines = [ln for ln in lines if not ln.endswith("invalid model file")] or lines
        mine = [ln for ln in lines if ln.startswith(p.field)]
        raise ParameterError(f"{p.describe(i)}: {'; '.join(mine or lines)}") from None


def _file_hashes(doc: dict[str, Any], base: Path) -> tuple[tuple[str, str], ...]:
    """SHA-256 of every matrix file a condensed body reads (a study depends on them too)."""
    out = []
    for body in doc.get("condensed_bodies", []):
        name = body.get("path")
        if not isinstance(name, str):
            continue
        f = Path(name) if Path(name).is_absolute() else base / name
        digest = hashlib.sha256(f.read_bytes()).hexdigest() if f.is_file() else "missing"
        out.append((name, digest))
    return tuple(out)
