"""Progress of long steps on stderr, also when it is not a terminal.

On a terminal, rich draws a spinner (or a bar with the count) and the elapsed time. In a log
(stderr piped or redirected) a step that lasts :data:`INTERVAL` seconds or more writes a
line every :data:`INTERVAL` seconds while it runs (with the count and the time left when
there is a count) and one when it ends; a shorter step writes nothing (so that an error
message stays the first line of stderr).

>>> import io
>>> from rich.console import Console
>>> log = Console(file=io.StringIO(), force_terminal=False)
>>> clock = iter([0.0, 0.0, 6.0, 6.0, 12.5, 12.5, 12.5]).__next__
>>> with counted("Floquet stability", 4, "speeds", console=log, clock=clock) as step:
...     for k in range(1, 5):
...         step(k)
>>> print(log.file.getvalue().strip())
Floquet stability: 2 of 4 speeds, 6 s, about 6 s left
Floquet stability: 4 of 4 speeds, done in 12 s
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    SpinnerColumn,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from .errors import err

__all__ = ["INTERVAL", "LogLines", "counted", "working"]

#: Seconds between two progress lines in a log (``RHEOLIN_PROGRESS_INTERVAL``).
INTERVAL = float(os.environ.get("RHEOLIN_PROGRESS_INTERVAL", "5"))


def _line(console: Console, text: str) -> None:
    console.print(text, markup=False, highlight=False, soft_wrap=True)


@contextlib.contextmanager
def working(
    what: str, *, console: Console | None = None, interval: float = INTERVAL
) -> Iterator[None]:
    """A step without a count: a spinner with the elapsed time on a terminal; in a log a
    line every ``interval`` seconds (from a timer thread, so also while the step computes)
    and one at the end of a long step."""
    out = console or err
    if out.is_terminal:
        columns = (SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn())
        with Progress(*columns, console=out, transient=True) as bar:
            bar.add_task(what, total=None)
            yield
        return
    start = time.monotonic()
    stop = threading.Event()

    def beat() -> None:
        while not stop.wait(interval):
            _line(out, f"{what}: {time.monotonic() - start:.0f} s ...")

    timer = threading.Thread(target=beat, name="rheolin-progress", daemon=True)
    timer.start()
    try:
        yield
    finally:
        stop.set()
        timer.join()
        seconds = time.monotonic() - start
        if seconds >= interval:
            _line(out, f"{what}: done in {seconds:.0f} s")


@contextlib.contextmanager
def counted(
    what: str,
    total: int,
    unit: str = "",
    *,
    console: Console | None = None,
    interval: float = INTERVAL,
    clock: Callable[[], float] = time.monotonic,
) -> Iterator[Callable[[int], None]]:
    """A step over ``total`` items: yields ``update(done)``. A bar with the count and the
    time left on a terminal; in a log at most one line every ``interval`` seconds as items
    finish, and one at the end of a long step."""
    out = console or err
    items = f" {unit}" if unit else ""
    if out.is_terminal:
        columns: Any = (
            TextColumn("{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TimeElapsedColumn(),
            TimeRemainingColumn(),
        )
        with Progress(*columns, console=out, transient=True) as bar:
            task = bar.add_task(what, total=total)
            yield lambda done: bar.update(task, completed=done)
        return
    lines = LogLines(out, what, total, items, interval, clock)
    yield lines.update
    lines.close()


class LogLines:
    """The lines of :func:`counted` in a log: one every ``interval`` seconds as items finish,
    with the time left, and one at the end of a long step."""

    def __init__(
        self,
        console: Console,
        what: str,
        total: int,
        items: str,
        interval: float,
        clock: Callable[[], float],
    ) -> None:
        self.console, self.what, self.total, self.items = console, what, total, items
        self.interval, self.clock = interval, clock
        self.start = self.last = clock()
        self.done = 0

    def update(self, done: int) -> None:
        """``done`` items are finished."""
        now = self.clock()
        self.done = done
        if now - self.last >= self.interval and 0 < done < self.total:
            left = (now - self.start) * (self.total - done) / done
            _line(
                self.console,
                f"{self.what}: {done} of {self.total}{self.items}, "
                f"{now - self.start:.0f} s, about {left:.0f} s left",
            )
            self.last = now

    def close(self) -> None:
        """The end line, for a step that took :attr:`interval` or longer."""
        seconds = self.clock() - self.start
        if seconds >= self.interval:
            _line(
                self.console,
                f"{self.what}: {self.done} of {self.total}{self.items}, done in {seconds:.0f} s",
            )
