"""Output directories: checked before any computation, filled as one set of files.

:func:`check_output_dir` refuses an output path that cannot be written (an existing file, a
directory that cannot be created or written) *before* the computation, with a message naming
the option. :func:`staged_output` writes a command's files into a staging directory beside
the output directory and moves them in together at the end: the files of the previous run
that this command owns are removed first, then the new ones renamed in. Whenever the process
is killed, the output directory holds the files of one run only (all of the previous, or all
or part of the new) and never a temporary file; a staging directory left by a killed process
is removed by the next run.

>>> import tempfile, pathlib
>>> out = pathlib.Path(tempfile.mkdtemp()) / "out"
>>> with staged_output(out, owned={"a.txt", "b.txt"}) as stage:
...     _ = (stage / "a.txt").write_text("new")
>>> sorted(p.name for p in out.iterdir())
['a.txt']
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path

from .._pause import pause
from ..errors import ModelError

__all__ = ["check_output_dir", "staged_output"]

_STAGE = ".{name}.partial-{pid}"
#: Longest output directory name [bytes]: 255 (the usual file-system limit) minus the staging
#: directory's prefix and suffix.
MAX_NAME = 255 - 40


def check_output_dir(path: str | Path, option: str = "--out") -> Path:
    """Refuse ``path`` as an output directory unless it can be created and written.

    Nothing is created: the nearest existing ancestor must be a directory in which a file can
    be created (tried, then removed, so it also holds for root and read-only file systems).

    >>> try:
    ...     check_output_dir(__file__)
    ... except ModelError as exc:
    ...     print(str(exc).endswith("is an existing file; give a directory (created)"))
    True
    """
    p = Path(path)
    if str(path).strip() == "":
        raise ModelError(f"{option}: empty path; give a directory, e.g. {option} results")
    if "\x00" in str(path):
        raise ModelError(f"{option}: the path {str(path)!r} contains a NUL character")
    for part in p.absolute().parts:
        if len(os.fsencode(part)) > MAX_NAME:
            raise ModelError(
                f"{option}: the path component {part[:40]!r}... has {len(os.fsencode(part))} "
                f"bytes; at most {MAX_NAME} are allowed (file systems allow 255, and rheolin "
                "stages the output beside it under a longer name)"
            )
    if p.exists() and not p.is_dir():
        raise ModelError(f"{option}: {str(p)!r} is an existing file; give a directory (created)")
    probe = p
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if probe.exists() and not probe.is_dir():
        raise ModelError(
            f"{option}: cannot create {str(p)!r}: {str(probe)!r} is a file, not a directory"
        )
    try:
        fd, name = tempfile.mkstemp(prefix=".rheolin-probe-", dir=probe)
    except OSError as exc:
        raise ModelError(
            f"{option}: cannot write in {str(probe)!r} ({exc.strerror}); give a writable directory"
        ) from None
    os.close(fd)
    os.unlink(name)
    return p


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # pragma: no cover - someone else's process
        return True
    return True


def _remove_stale_stages(where: Path, name: str) -> None:
    """Staging directories of killed runs (their process is gone)."""
    prefix = _STAGE.format(name=name, pid="")
    with contextlib.suppress(OSError):
        for d in where.iterdir():
            if d.name.startswith(prefix) and d.is_dir():
                pid = d.name[len(prefix) :]
                if pid.isdigit() and int(pid) != os.getpid() and not _alive(int(pid)):
                    shutil.rmtree(d, ignore_errors=True)


@contextlib.contextmanager
def staged_output(out: str | Path, owned: Iterable[str]) -> Iterator[Path]:
    """Yield a staging directory; on success move its files into ``out`` as one set.

    ``owned``: the file names the command writes into ``out`` (its files of an earlier run,
    removed before the new ones are moved in, so the directory never mixes two runs). Other
    files in ``out`` are left alone. On an exception (Ctrl-C included) ``out`` is untouched
    and the staging directory removed.
    """
    target = Path(out).absolute()
    parent = target.parent
    parent.mkdir(parents=True, exist_ok=True)
    _remove_stale_stages(parent, target.name)
    stage = parent / _STAGE.format(name=target.name, pid=os.getpid())
    shutil.rmtree(stage, ignore_errors=True)
    try:  # made inside the try: a Ctrl-C right after the mkdir still removes it
        try:
            stage.mkdir()
        except OSError:  # the parent is not writable, the directory itself is: stage inside
            stage = target / _STAGE.format(name="", pid=os.getpid())
            stage.mkdir(parents=True)
        yield stage
        pause("staging")  # fault injection for the kill tests (rheolin._pause)
        new = sorted(p.name for p in stage.iterdir() if p.is_file())
        target.mkdir(parents=True, exist_ok=True)
        for name in sorted(set(owned) | set(new)):  # the earlier run's files go first
            with contextlib.suppress(FileNotFoundError):
                (target / name).unlink()
        for name in new:
            os.replace(stage / name, target / name)
        _fsync_dir(target)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def _fsync_dir(path: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(path, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
