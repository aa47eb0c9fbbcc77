"""The CLI's error contract: what every command does when something goes wrong.

* a user error (a :class:`~rheolin.ModelError`, a unit, a refused memory estimate, a bad
  option) prints ``error: <field>: <what was given and what is allowed>`` -- one plain line
  per problem, never read as Rich markup -- and exits with :data:`EXIT_INPUT` (2);
* an internal error (a bug) prints one short line and exits with :data:`EXIT_INTERNAL` (3);
  ``rheolin --debug ...`` (or ``RHEOLIN_DEBUG=1``) adds the traceback;
* Ctrl-C (or SIGTERM) stops the command, says what was kept and exits with
  :data:`EXIT_INTERRUPTED` (130);
* a closed standard output (``rheolin ... | head``) ends the command quietly with
  :data:`EXIT_FAILED` (1), as Python's documentation advises for a broken pipe.

The contract lives in :class:`ContractGroup` (the click group behind ``rheolin``), so it holds
for ``python -m rheolin.cli``, the ``rheolin`` script and ``typer.testing.CliRunner`` alike.
"""

from __future__ import annotations

import _thread
import contextlib
import os
import re
import signal
import sys
import threading
import traceback
from collections.abc import Iterator
from typing import Any, NoReturn

import typer
from rich.console import Console
from typer.core import TyperGroup

try:  # typer >= 0.2x carries its own copy of click
    from typer._click.exceptions import NoArgsIsHelpError, UsageError
except ImportError:  # pragma: no cover - typer on the click package
    from click.exceptions import NoArgsIsHelpError, UsageError  # type: ignore[assignment]

from ..budget import MemoryBudgetError, check_settings, format_bytes, process_headroom
from ..errors import ModelError
from ..io.units import UnitError

__all__ = [
    "EXIT_FAILED",
    "EXIT_INPUT",
    "EXIT_INTERNAL",
    "EXIT_INTERRUPTED",
    "ContractGroup",
    "UserError",
    "err",
    "plain_error",
    "set_debug",
    "set_kept",
    "sigterm_as_interrupt",
]

#: The computation ran but did not succeed (not converged, unstable, undecided stability).
EXIT_FAILED = 1
#: Invalid input: model file, option, output path, memory estimate over the budget.
EXIT_INPUT = 2
#: An internal error (a bug): please report it with the output of ``rheolin --debug ...``.
EXIT_INTERNAL = 3
#: Interrupted (Ctrl-C, SIGTERM).
EXIT_INTERRUPTED = 130

#: The terminal for messages. No emoji codes (``6000:100:100rpm`` must not become an emoji),
#: no highlighting; user text is printed with ``markup=False`` (see :func:`plain_error`).
err = Console(stderr=True, emoji=False, highlight=False)

_STATE: dict[str, Any] = {"debug": False, "kept": None, "running": False}


class UserError(Exception):
    """An invalid input the CLI found itself (an option, an output path): exit 2."""


#: Exceptions that mean "the input is wrong" (exit 2), whatever raised them.
USER_ERRORS: tuple[type[BaseException], ...] = (
    ModelError,
    UnitError,
    MemoryBudgetError,
    UserError,
)


def set_debug(flag: bool) -> None:
    """Show tracebacks of internal errors (``rheolin --debug``)."""
    _STATE["debug"] = bool(flag)


def set_kept(message: str | None) -> None:
    """What an interruption from now on leaves behind (said on Ctrl-C)."""
    _STATE["kept"] = message


def _debug() -> bool:
    return bool(_STATE["debug"]) or os.environ.get("RHEOLIN_DEBUG", "") not in ("", "0")


def one_line(message: str) -> str:
    """A loader message ``"file: invalid model file\\n  path: msg"`` with one problem as one
    line ``"file: path: msg"``; several problems stay one line each.

    >>> one_line("m.toml: invalid model file\\n  shafts[0].density: must be > 0, got -1")
    'm.toml: shafts[0].density: must be > 0, got -1'
    """
    lines = [ln.strip() for ln in str(message).strip().splitlines() if ln.strip()]
    head = re.match(r"^(.*): invalid model file$", lines[0]) if lines else None
    if head and len(lines) == 2:
        return f"{head.group(1)}: {lines[1]}"
    return "\n".join(lines) if lines else "(no message)"


def plain_error(message: str, prefix: str = "error") -> None:
    """Print ``prefix: message`` to stderr as plain text (no markup, no emoji)."""
    text = one_line(message)
    lines = text.splitlines()
    if len(lines) > 1:  # several problems: a heading line, then one line per problem
        text = lines[0] + "".join(f"\n  {ln}" for ln in lines[1:])
    err.print(f"{prefix}: {text}", markup=False, emoji=False, highlight=False, soft_wrap=True)


def _interrupted() -> None:
    kept = _STATE["kept"] or "nothing was written"
    err.print(f"interrupted: {kept}", markup=False, highlight=False, soft_wrap=True)
    if not _debug():
        # objects the interrupt cut short mid-construction (an h5netcdf file) fail in their
        # finalizers at exit; Python prints those as "Exception ignored" tracebacks
        sys.unraisablehook = lambda unraisable: None


def _internal(exc: BaseException) -> None:
    if _debug():
        traceback.print_exception(exc, file=sys.stderr)
    where = traceback.extract_tb(exc.__traceback__)[-1:] if exc.__traceback__ else []
    at = f" (at {os.path.basename(where[0].filename)}:{where[0].lineno})" if where else ""
    hint = "" if _debug() else "; rerun with `rheolin --debug ...` for the traceback"
    err.print(
        f"internal error: {type(exc).__name__}: {exc}{at}{hint}. This is a bug in rheolin, "
        "not in your input: please report it.",
        markup=False,
        highlight=False,
        soft_wrap=True,
    )


def _quiet_stdout() -> None:
    """Point stdout at /dev/null, so that flushing it at exit does not fail again (the
    Python documentation's advice for SIGPIPE)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # a stdout without a file (CliRunner)
        pass


def _out_of_memory(exc: BaseException) -> None:
    """An allocation failed although the estimate fit: say so, with the limits that apply,
    and what to lower (the input is too large for this process, not a bug)."""
    room = ", ".join(f"{k} {format_bytes(v)}" for k, v in process_headroom().items())
    plain_error(
        "memory: the computation ran out of memory although its estimate fit the budget "
        f"({type(exc).__name__}{': ' + str(exc) if str(exc) else ''}); room now: "
        f"{room or 'unknown'}. Lower RHEOLIN_SOLVE_MEMORY / RHEOLIN_MEMORY_BUDGET, the "
        "harmonic order or the model size"
    )


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """SIGTERM (a batch system's stop) ends the command like Ctrl-C."""

    def interrupt(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    try:
        old = signal.signal(signal.SIGTERM, interrupt)
    except ValueError:  # not the main thread: leave SIGTERM alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


def exit_with(code: int) -> NoReturn:
    """Leave the command with ``code`` (through click, so CliRunner sees it too)."""
    raise typer.Exit(code)


def _interrupting_signal() -> signal.Signals:
    """The signal whose Python handler raises the interrupt in the main thread: SIGINT, or
    SIGTERM when SIGINT is ignored (a batch job or a background ``cmd &`` of a script, where
    the stop comes as SIGTERM through :func:`sigterm_as_interrupt`)."""
    if callable(signal.getsignal(signal.SIGINT)):
        return signal.SIGINT
    if callable(signal.getsignal(signal.SIGTERM)):
        return signal.SIGTERM
    return signal.SIGINT  # neither is Python's: nothing can be redelivered


def _redelivering(previous: Any) -> Any:
    """An unraisable-exception hook that gives a Ctrl-C back to the command: one landing in a
    finalizer or weakref callback is printed and dropped by Python (the command would go on
    and print a traceback); it is raised again in the main thread once the callback returns."""

    def again() -> None:
        if _STATE.get("running"):
            _thread.interrupt_main(_interrupting_signal())

    def hook(unraisable: Any) -> None:
        if unraisable.exc_type is not None and issubclass(unraisable.exc_type, KeyboardInterrupt):
            threading.Timer(0.1, again).start()  # after the callback has returned
            return
        previous(unraisable)

    return hook


class ContractGroup(TyperGroup):
    """The ``rheolin`` command group with the error contract of this module."""

    def invoke(self, ctx: Any) -> Any:
        previous = sys.unraisablehook
        hook = sys.unraisablehook = _redelivering(previous)
        _STATE["running"] = True
        try:
            return self._invoke(ctx)
        finally:
            _STATE["running"] = False
            if sys.unraisablehook is hook:  # not replaced on the way out (_interrupted)
                sys.unraisablehook = previous

    def _invoke(self, ctx: Any) -> Any:
        try:
            set_kept(None)  # an earlier command's files (in-process callers) are not this one's
            check_settings()  # the budget variables, before any work
            return super().invoke(ctx)
        except typer.Exit:
            raise
        except NoArgsIsHelpError:
            raise
        except UsageError as exc:
            where = exc.ctx.command_path if exc.ctx is not None else "rheolin"
            plain_error(f"{where}: {exc.format_message()} (see `{where} --help`)")
            exit_with(EXIT_INPUT)
        except BrokenPipeError:  # the reader of stdout went away (`rheolin ... | head`)
            _quiet_stdout()
            exit_with(EXIT_FAILED)
        except (KeyboardInterrupt, typer.Abort):
            _interrupted()
            exit_with(EXIT_INTERRUPTED)
        except USER_ERRORS as exc:
            plain_error(str(exc))
            exit_with(EXIT_INPUT)
        except MemoryError as exc:
            _out_of_memory(exc)
            exit_with(EXIT_INPUT)
        except RecursionError as exc:  # input nested deeper than any model file needs
            plain_error(f"input: nested too deeply to read ({exc})")
            exit_with(EXIT_INPUT)
        except Exception as exc:
            _internal(exc)
            exit_with(EXIT_INTERNAL)
