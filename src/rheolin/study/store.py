"""The checkpoint of a study: one NetCDF file per finished chunk plus a manifest.

Layout of an output directory ``DIR``::

    DIR/checkpoint/manifest.json       the study's identity and key, its memory budget
    DIR/checkpoint/chunk-0000120.nc     points 120, 121, ... (each file written atomically)
    DIR/checkpoint/map-000003.pkl       refined stability map of combination 3 (a cache)
    DIR/.rheolin.lock                   held while a study runs (a second run is refused)
    DIR/sweep.nc, sweep.json, ...       the results, written when every point is done

The manifest is written once, before any chunk; a chunk file exists completely or not at all
(temporary file, fsync, rename), so a study killed at any moment leaves readable files, and
the set of chunk files is the set of finished points. Per-chunk NetCDF was chosen over a Zarr
store by measurement (``bench/results/sweep.md``): a few ms more per chunk, but each chunk is
one self-contained file committed by one rename, with no array shapes to fix in advance.
"""

from __future__ import annotations

import contextlib
import datetime
import json
import logging
import os
import pickle
import re
import shutil
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import xarray as xr

from .._pause import pause
from ..errors import ModelError
from ..io.atomic import atomic_write
from ..results.dataset import netcdf_engine
from .chunks import read_chunk, write_chunk
from .spec import StudySpec

__all__ = [
    "CHECKPOINT",
    "OUTPUTS",
    "CheckpointStore",
    "MemoryStore",
    "StudyBusy",
    "StudyConflict",
    "output_files",
]

log = logging.getLogger(__name__)

CHECKPOINT = "checkpoint"
LOCK = ".rheolin.lock"
MANIFEST = "manifest.json"
#: Result files a study writes into its directory (``vary_*.png``: one per parameter).
OUTPUTS = ("sweep.nc", "sweep.json", "sweep.png", "stability_map.nc", "stability_map.png")
_OUTPUT = re.compile(r"^(?:" + "|".join(map(re.escape, OUTPUTS)) + r"|vary_.+\.png)$")
_TEMP = re.compile(r"^\.(.+)\.[A-Za-z0-9_]+\.tmp$")  # rheolin.io.atomic's temporary files


class StudyConflict(ModelError):
    """The output directory holds results of a different study."""


class StudyBusy(ModelError):
    """Another process is running a study in the same output directory."""


def output_files(directory: Path) -> list[Path]:
    """The study result files present in ``directory``."""
    if not directory.is_dir():
        return []
    return sorted(p for p in directory.iterdir() if p.is_file() and _OUTPUT.match(p.name))


class MemoryStore:
    """No checkpoint: chunks kept in memory (the Python API without an output directory)."""

    def __init__(self) -> None:
        self.chunks: list[xr.Dataset] = []
        self.discarded: list[str] = []
        self.budget: int | None = None

    def done(self) -> set[int]:
        return {int(p) for ds in self.chunks for p in ds["point"].values}

    def write(self, ds: xr.Dataset) -> None:
        self.chunks.append(ds)

    def read_all(self) -> list[xr.Dataset]:
        return list(self.chunks)

    def load_map(self, combo: int, refine: float) -> Any:
        return None

    def save_map(self, combo: int, refine: float, smap: Any) -> None:
        pass


class CheckpointStore(MemoryStore):
    """The checkpoint in ``directory/checkpoint`` (see the module docstring).

    Use as a context manager around :meth:`open`: the lock is held until it exits.
    """

    def __init__(self, directory: str | Path) -> None:
        super().__init__()
        self.directory = Path(directory)
        self.path = self.directory / CHECKPOINT
        self._lock: Any = None
        self._done: dict[int, Path] = {}
        # the chunks written by this run, as written (a NetCDF file reads back identical), so
        # that assembling them needs no second read
        self._written: dict[Path, xr.Dataset] = {}

    # ------------------------------------------------------------------ opening
    def open(self, spec: StudySpec, *, budget: int, overwrite: bool = False) -> int:
        """Lock the directory, remove stale temporary files, check that the checkpoint (if
        any) belongs to ``spec``, create it if new. Returns the memory budget of the study
        (the one stored when it was created).

        Raises
        ------
        StudyConflict
            The directory holds another study's points or results (unless ``overwrite``:
            then they are removed).
        StudyBusy
            Another process holds the lock.
        """
        self.directory.mkdir(parents=True, exist_ok=True)
        self._acquire()
        self._remove_temporaries()
        manifest = self._read_manifest()
        chunks = self._chunk_paths()
        if manifest is not None and manifest.get("key") == spec.key:
            self.budget = int(manifest["memory_budget"])
            self._scan(spec.key)
            return self.budget
        stale = output_files(self.directory)
        if manifest is not None or chunks or stale:
            if not overwrite:
                raise StudyConflict(self._conflict(spec, manifest, len(chunks), stale))
            for p in stale:
                p.unlink()
            shutil.rmtree(self.path, ignore_errors=True)
        self.path.mkdir(parents=True, exist_ok=True)
        created = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
        manifest = {
            "key": spec.key,
            "identity": spec.identity(),
            "memory_budget": int(budget),
            "created": created,
            "points": spec.n_points,
            "source": spec.source,
        }
        with atomic_write(self.path / MANIFEST) as tmp:
            tmp.write_text(json.dumps(manifest, indent=1) + "\n")
        self.budget = int(budget)
        self._done = {}
        return self.budget

    def close(self) -> None:
        """Release the lock."""
        if self._lock is not None:
            self._lock.close()
            self._lock = None

    def __enter__(self) -> CheckpointStore:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    # ------------------------------------------------------------------ chunks
    def done(self) -> set[int]:
        """Points in the chunk files."""
        return set(self._done)

    def write(self, ds: xr.Dataset) -> None:
        """Write one chunk file (atomically)."""
        first = int(ds["point"].values[0])
        path = self.path / f"chunk-{first:07d}.nc"
        n = 1
        while path.exists():  # not expected: points are written once
            path = self.path / f"chunk-{first:07d}-{n}.nc"
            n += 1
        write_chunk(ds, path)
        self._written[path] = ds
        self._done.update(dict.fromkeys((int(p) for p in ds["point"].values), path))
        pause("chunk")  # fault injection for the kill tests (rheolin._pause)

    def read_all(self) -> list[xr.Dataset]:
        """Every chunk, in memory (each point once)."""
        out = []
        for path in sorted(set(self._done.values())):
            ds = self._written[path] if path in self._written else read_chunk(path)
            keep = [self._done.get(int(p)) == path for p in ds["point"].values]
            out.append(ds if all(keep) else ds.isel(point=keep))
        return out

    # ------------------------------------------------------------------ maps
    def load_map(self, combo: int, refine: float) -> Any:
        path = self.path / f"map-{combo:06d}.pkl"
        try:
            saved = pickle.loads(path.read_bytes())
        except (OSError, pickle.UnpicklingError, EOFError, AttributeError):
            return None
        return saved["map"] if saved.get("refine") == refine else None

    def save_map(self, combo: int, refine: float, smap: Any) -> None:
        with atomic_write(self.path / f"map-{combo:06d}.pkl") as tmp:
            tmp.write_bytes(pickle.dumps({"refine": refine, "map": smap}))

    def remove_outputs(self, keep: Iterable[str]) -> list[Path]:
        """Remove result files of an earlier run of this study that this run does not write
        (e.g. ``stability_map.png`` when the map is now off)."""
        names = set(keep)
        gone = [p for p in output_files(self.directory) if p.name not in names]
        for p in gone:
            p.unlink()
        return gone

    # ------------------------------------------------------------------ internals
    def _acquire(self) -> None:
        try:
            import fcntl
        except ImportError:  # pragma: no cover - not POSIX: no lock
            return
        fh = open(self.directory / LOCK, "a+")
        try:
            fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            fh.close()
            raise StudyBusy(
                f"{self.directory}: another rheolin study is running in this directory"
            ) from None
        self._lock = fh

    def _remove_temporaries(self) -> None:
        """Temporary files of writes that a kill interrupted (we hold the lock)."""
        for folder, wanted in ((self.path, None), (self.directory, _OUTPUT)):
            if not folder.is_dir():
                continue
            for p in folder.iterdir():
                m = _TEMP.match(p.name)
                if m and (wanted is None or wanted.match(m.group(1))):
                    with contextlib.suppress(OSError):
                        p.unlink()
                        log.info("removed the stale temporary file %s", p)

    def _read_manifest(self) -> dict[str, Any] | None:
        path = self.path / MANIFEST
        if not path.exists():
            return None
        try:
            data = json.loads(path.read_text())
        except (OSError, ValueError):
            return {"key": None, "identity": {}}
        return data if isinstance(data, dict) else {"key": None, "identity": {}}

    def _chunk_paths(self) -> list[Path]:
        return sorted(self.path.glob("chunk-*.nc")) if self.path.is_dir() else []

    def _scan(self, key: str) -> None:
        """Which points the chunk files hold; a file that cannot be read, or that belongs to
        another study, is set aside (renamed ``*.unreadable``) and its points recomputed."""
        self._done = {}
        for path in self._chunk_paths():
            try:
                with xr.open_dataset(path, engine=netcdf_engine()) as ds:
                    if ds.attrs.get("study_key") != key:
                        raise ValueError("the chunk belongs to another study")
                    points = [int(p) for p in ds["point"].values]
            except Exception as exc:  # an unreadable file must not stop the study
                log.warning("set aside the chunk file %s: %s", path, exc)
                os.replace(path, path.with_name(path.name + ".unreadable"))
                self.discarded.append(path.name)
                continue
            for p in points:
                self._done.setdefault(p, path)

    def _conflict(
        self, spec: StudySpec, manifest: dict[str, Any] | None, chunks: int, stale: list[Path]
    ) -> str:
        where = str(self.directory)
        fix = "use --overwrite (overwrite=True) to discard them, or another output directory"
        if manifest is not None:
            why = spec.difference(manifest.get("identity") or {}) or "its manifest is unreadable"
            return f"{where} holds {chunks} finished chunks of a different study ({why}); {fix}"
        if chunks:
            return f"{where}/{CHECKPOINT} holds chunk files without a manifest; {fix}"
        names = ", ".join(p.name for p in stale)
        return f"{where} holds results of an earlier run ({names}); {fix}"
