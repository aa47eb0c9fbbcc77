"""What a result directory holds: its files read back, the model file it was computed from
(found by the path the results record, checked by its SHA-256), and the versions.

>>> import tempfile
>>> d = read_directory(tempfile.mkdtemp())
>>> d.kinds, d.notes[0][:30]
([], 'no rheolin result file in this')
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import xarray as xr

__all__ = ["FILES", "ResultDirectory", "read_directory"]

#: The result files a report reads, by the command that writes them.
FILES = {
    "results.nc": "run",
    "summary.json": "run",
    "sweep.nc": "sweep",
    "sweep.json": "sweep",
    "stability_map.nc": "stability map",
    "campbell.nc": "campbell",
    "modes.nc": "modes",
    "frf.nc": "frf",
    "critical_map.nc": "critical-map",
}


@dataclass
class ResultDirectory:
    """The files of one result directory, read back (missing ones None). ``notes``: what the
    report says first; ``left_out``: those of them that leave a part of the report out (a
    result file not used, and why), which ``rheolin report`` also warns of on the console."""

    path: Path
    datasets: dict[str, xr.Dataset] = field(default_factory=dict)
    tables: dict[str, dict[str, Any]] = field(default_factory=dict)
    images: dict[str, bytes] = field(default_factory=dict)
    model: Any = None
    model_path: Path | None = None
    model_sha256: str = ""
    notes: list[str] = field(default_factory=list)
    left_out: list[str] = field(default_factory=list)

    def leave_out(self, note: str) -> None:
        """Say in the notes that a part is left out, and why."""
        self.notes.append(note)
        self.left_out.append(note)

    @property
    def kinds(self) -> list[str]:
        """The commands whose files are here (``run``, ``sweep``, ``campbell``, ...)."""
        names = [*self.datasets, *self.tables]
        return list(dict.fromkeys(FILES[n] for n in FILES if n in names))

    def recorded(self, key: str) -> Any:
        """``key`` as the results record it (JSON tables first, then file attributes)."""
        for table in self.tables.values():
            if table.get(key) not in (None, ""):
                return table[key]
        for ds in self.datasets.values():
            if ds.attrs.get(key) not in (None, ""):
                return ds.attrs[key]
        return None


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _find_model(d: ResultDirectory, given: Path | None) -> None:
    """Load the model: ``given``, else the recorded ``model_file`` (as written, or beside
    the results); say what was found and whether its hash matches the results'."""
    from ..io import read_model

    recorded = d.recorded("model_file")
    expected = str(d.recorded("model_sha256") or "")
    candidates = [given] if given is not None else []
    if recorded:
        candidates += [Path(recorded), d.path / Path(recorded).name, d.path.parent / recorded]
    path = next((p for p in candidates if p is not None and p.is_file()), None)
    if path is None:
        if recorded or given is not None:
            d.notes.append(
                f"the model file {str(given or recorded)!r} was not found: no drawing "
                "(give it: rheolin report DIR --model FILE)"
            )
        return
    try:
        lm = read_model(path)
    except Exception as exc:  # an invalid file: the report says so and goes on
        d.notes.append(f"the model file {str(path)!r} could not be read: {exc}")
        return
    d.model, d.model_path, d.model_sha256 = lm, path, lm.sha256
    if expected and lm.sha256 != expected:
        d.notes.append(
            f"the model file {str(path)!r} has changed since these results were computed "
            f"(SHA-256 {lm.sha256[:12]}... now, {expected[:12]}... then): the drawing and "
            "the model's inputs show the file as it is now"
        )


def _in_file_units(d: ResultDirectory) -> None:
    """Frequencies that files of earlier versions stored in rad/s, in Hz as the files are
    now (docs/results-schema.md, Units)."""
    for name, variables in (
        ("campbell.nc", ("frequency", "critical_frequency")),
        ("stability_map.nc", ("frequency",)),
    ):
        ds = d.datasets.get(name)
        for v in variables:
            if ds is not None and v in ds and ds[v].attrs.get("units", "rad/s") == "rad/s":
                ds[v] = ds[v] / (2 * math.pi)
                ds[v].attrs["units"] = "Hz"


def read_directory(path: str | Path, model: str | Path | None = None) -> ResultDirectory:
    """Read every result file of directory ``path`` (and the model file, see
    :class:`ResultDirectory`); a file that cannot be read is named in ``notes``."""
    d = ResultDirectory(Path(path))
    for name in FILES:
        p = d.path / name
        if not p.is_file():
            continue
        try:
            if name.endswith(".json"):
                table = json.loads(p.read_text(encoding="utf-8"))
                if not isinstance(table, dict):
                    raise ValueError(f"a JSON {type(table).__name__}, not an object")
                d.tables[name] = table
            else:
                with xr.open_dataset(p) as ds:
                    d.datasets[name] = ds.load()
        except (OSError, ValueError, RecursionError) as exc:  # not a file rheolin wrote
            d.leave_out(f"{name} could not be read: {exc}")
    _in_file_units(d)
    for p in sorted(d.path.glob("*.png")):
        d.images[p.name] = p.read_bytes()
    if not d.datasets and not d.tables:
        d.notes.append(f"no rheolin result file in this directory ({', '.join(FILES)})")
        return d
    _find_model(d, None if model is None else Path(model))
    return d


def file_digests(d: ResultDirectory) -> list[tuple[str, int, str]]:
    """``(name, bytes, sha256)`` of the result files, for the report's traceability table."""
    out = []
    for name in [*FILES, *d.images]:
        p = d.path / name
        if p.is_file():
            out.append((name, p.stat().st_size, _sha256(p)))
    return out
