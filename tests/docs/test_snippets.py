"""Every code block in README.md and docs/*.md runs as written, and every name the prose gives
(``rheolin.*``, ``rl.*``, ``Model.*``, ``rheolin <command> --option``, files, tests) exists.

How a block is treated follows its fence:

* ```python: run. All blocks of one document share one namespace and run in document order,
  interleaved with its commands, in a fresh temporary directory.
* ```console and ```sh: one command per line (``\\`` continues a line, ``#`` starts a
  comment). ``rheolin ...`` lines run in that directory with this interpreter's rheolin and
  must exit 0, or N when the comment starts with ``exit code N``: a plain
  ``rheolin ARGS [> FILE]`` in the document's process (:func:`run_rheolin`), others in bash.
  Install lines (``git clone``, ``cd``, ``pip install``, ``make``) are not run; their extras
  and make targets are checked against pyproject.toml and the Makefile.
* ```toml: parsed; with ``<!-- file: NAME -->`` on the line before the fence, also written to
  NAME in the directory before the next block runs.
* ```text and ```json: output and excerpts, not run.

A fence without a language fails. Each document gets ``TIMEOUT`` seconds in its own process
group (killed at the end, with any worker processes).
"""

from __future__ import annotations

import ast
import contextlib
import importlib
import inspect
import json
import os
import re
import resource
import shlex
import signal
import subprocess
import sys
import textwrap
import tomllib
import traceback
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from unittest import mock

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: Wall-clock seconds per document: about 8 times the CPU time of the slowest (README.md,
#: about 40 s), so that a loaded machine passes and a hang still fails.
TIMEOUT = 300.0
RUN = {"python", "console", "sh", "toml"}
READ = {"text", "json"}
FENCE = re.compile(r"^(\s*)```(\S*)\s*$")
FILE_TAG = re.compile(r"^\s*<!--\s*file:\s*(\S+)\s*-->\s*$")
EXIT_CODE = re.compile(r"^exit code (\d+)\b")
INSTALL = ("git clone ", "cd ", "pip install ", "make ")
#: Characters a shell interprets (besides one ``> FILE``): such a line runs through bash.
SHELL = frozenset("|&;<()$`\\*?[]{}~!\n")


@dataclass
class Block:
    """A fenced block: its language, first line number (1-based, of the code), text, and the
    file name a ``<!-- file: NAME -->`` tag gives it."""

    lang: str
    line: int
    text: str
    file: str | None = None


def blocks(path: Path) -> list[Block]:
    """The fenced blocks of a Markdown file, in order (indented ones inside lists dedented)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    out: list[Block] = []
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        tag = FILE_TAG.match(lines[i - 1]) if i > 0 else None
        indent = len(m.group(1))
        j = i + 1
        while j < len(lines) and not lines[j].strip().startswith("```"):
            j += 1
        if j == len(lines):
            raise AssertionError(f"{path.name}:{i + 1}: unclosed code fence")
        text = "\n".join(x[indent:] for x in lines[i + 1 : j]) + "\n"
        out.append(Block(m.group(2), i + 2, text, tag.group(1) if tag else None))
        i = j + 1
    return out


def commands(block: Block) -> list[tuple[int, str, int]]:
    """``(line, command, expected exit code)`` of a shell block; continuation lines joined."""
    out = []
    pending: list[str] = []
    start = block.line
    for k, raw in enumerate(block.text.splitlines()):
        line = raw.rstrip()
        if not pending:
            start = block.line + k
        if line.endswith("\\"):
            pending.append(line[:-1])
            continue
        text = " ".join(s.strip() for s in [*pending, line]).strip()
        pending = []
        if text.startswith("$ "):
            text = text[2:]
        command, _, comment = text.partition(" #")
        if text.startswith("#"):
            command, comment = "", text[1:]
        command = command.strip()
        if not command:
            continue
        code = EXIT_CODE.match(comment.strip())
        out.append((start, command, int(code.group(1)) if code else 0))
    assert not pending, f"line {start}: a command ends in a continuation"
    return out


def extras() -> set[str]:
    """The optional-dependency groups of pyproject.toml."""
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    return set(meta["project"]["optional-dependencies"])


def make_targets() -> set[str]:
    """The targets the Makefile defines."""
    text = (ROOT / "Makefile").read_text(encoding="utf-8")
    return set(re.findall(r"^([A-Za-z][\w-]*):", text, flags=re.M))


def check_install_line(where: str, command: str) -> None:
    """An install step is not run: its extras and make target must exist."""
    if command.startswith("pip install "):
        for spec in re.findall(r"\[([\w,\s-]+)\]", command):
            unknown = {e.strip() for e in spec.split(",")} - extras()
            assert not unknown, f"{where}: unknown extras {sorted(unknown)} in {command!r}"
    elif command.startswith("make "):
        target = command.split()[1]
        assert target in make_targets(), f"{where}: no make target {target!r}"


def steps(path: Path) -> list[dict[str, Any]]:
    """What the driver runs for one document, in order; fails on a block it cannot place."""
    out: list[dict[str, Any]] = []
    for b in blocks(path):
        where = f"{path.name}:{b.line}"
        assert b.lang in RUN | READ, (
            f"{where}: a code fence needs a language: python, console, sh, toml (run or "
            f"checked) or text, json (output, not run); got {b.lang!r}"
        )
        if b.lang == "python":
            out.append({"kind": "python", "where": where, "line": b.line, "code": b.text})
        elif b.lang == "toml":
            try:
                tomllib.loads(b.text)
            except tomllib.TOMLDecodeError as exc:
                raise AssertionError(f"{where}: not valid TOML: {exc}") from None
            if b.file:
                out.append({"kind": "file", "where": where, "name": b.file, "text": b.text})
        elif b.lang in ("console", "sh"):
            for line, command, code in commands(b):
                here = f"{path.name}:{line}"
                if command.startswith("rheolin ") or command == "rheolin":
                    out.append({"kind": "sh", "where": here, "command": command, "code": code})
                else:
                    assert command.startswith(INSTALL), (
                        f"{here}: only `rheolin ...` commands and install steps belong in a "
                        f"shell block, got {command!r}"
                    )
                    check_install_line(here, command)
    return out


def plain_command(command: str) -> tuple[list[str], str | None] | None:
    """``(ARGS, FILE)`` of ``rheolin ARGS [> FILE]`` with nothing else for a shell (pipes,
    ``&&``, ``$``, globs, ``2>``, backticks, open quotes), else None.

    >>> plain_command("rheolin example rotor > 'my rotor.toml'")
    (['example', 'rotor'], 'my rotor.toml')
    >>> [plain_command(c) for c in ("rheolin run m.toml 2> e", "rheolin x | head", "rheolin a>b")]
    [None, None, None]
    """
    if SHELL & set(command):
        return None
    head, redirect, target = command.partition(">")
    if ">" in target or (redirect and not head[-1:].isspace()):  # `>>`, `2>`, `a>b`
        return None
    try:
        words, out = shlex.split(head), shlex.split(target)
    except ValueError:  # a quote left open (a quoted `>`): bash says what it makes of it
        return None
    if words[:1] != ["rheolin"] or len(out) != len(redirect):
        return None
    return words[1:], out[0] if out else None


def run_rheolin(args: list[str], out: str | None, env: dict[str, str], filters: list) -> int:
    """``rheolin ARGS [> OUT]`` through the application object in this process; its exit
    status. It starts as a new process does: environment ``env``, consoles ``COLUMNS`` wide,
    NumPy's default error handling, the first warning ``filters``, stdout (``OUT`` truncated
    as bash does) and stderr at their file descriptors; those, the directory, signal handlers
    and ``sys.unraisablehook`` (an interrupt silences it) are put back after."""
    import numpy as np

    from rheolin.cli.app import app
    from rheolin.cli.common import console
    from rheolin.cli.errors import err

    widths = [(c, c._width) for c in (console, err)]
    hooks = sys.unraisablehook, sys.excepthook
    handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    for f in (sys.stdout, sys.stderr):
        f.flush()
    fds = os.dup(1), os.dup(2)
    try:
        for c, _ in widths:  # a console takes its width from COLUMNS when it is made
            c._width = int(env["COLUMNS"]) if env.get("COLUMNS", "").isdigit() else None
        if out is not None:
            os.dup2(fd := os.open(out, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o666), 1)
            os.close(fd)
        with (
            mock.patch.dict(os.environ, env, clear=True),
            contextlib.chdir(Path.cwd()),
            warnings.catch_warnings(),
            np.errstate(divide="warn", over="warn", under="ignore", invalid="warn"),
        ):
            warnings.filters = list(filters)  # a command may add to it
            try:
                app(args, prog_name="rheolin", standalone_mode=True)
            except SystemExit as exc:  # as Python's exit status (click gives an int)
                return exc.code % 256 if isinstance(exc.code, int) else int(exc.code is not None)
            except Exception:  # what escapes the application ends a process like this
                traceback.print_exc()
                return 1
            return 0
    finally:
        for f in (sys.stdout, sys.stderr):
            f.flush()
        for fd, target in zip(fds, (1, 2), strict=True):
            os.dup2(fd, target)
            os.close(fd)
        for c, w in widths:
            c._width = w
        sys.unraisablehook, sys.excepthook = hooks
        for s, h in handlers.items():
            if h is not None:
                signal.signal(s, h)


def driver(plan: list[dict[str, Any]], rheolin: str) -> None:
    """Run the steps of one document in the current directory (the child process)."""
    filters = list(warnings.filters)
    sys.stdout.reconfigure(line_buffering=True)  # type: ignore[union-attr]
    namespace: dict[str, Any] = {"__name__": "__main__"}
    env = dict(os.environ, PATH=f"{Path(rheolin).parent}{os.pathsep}{os.environ['PATH']}")
    for step in plan:
        cpu = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
        print(f"--- {step['where']} (CPU so far {sum(r.ru_utime + r.ru_stime for r in cpu):.1f} s)")
        if step["kind"] == "python":
            code = "\n" * (step["line"] - 1) + step["code"]  # tracebacks point at the doc line
            exec(compile(code, step["where"].split(":")[0], "exec"), namespace)
        elif step["kind"] == "file":
            Path(step["name"]).write_text(step["text"], encoding="utf-8")
        else:
            print(f"$ {step['command']}", flush=True)
            plain = plain_command(step["command"])
            if plain is not None:
                returncode = run_rheolin(*plain, env, filters)
            else:
                returncode = subprocess.run(
                    ["bash", "-o", "pipefail", "-c", step["command"]], env=env, check=False
                ).returncode
            if returncode != step["code"]:
                raise SystemExit(
                    f"{step['where']}: `{step['command']}` exited {returncode}, "
                    f"the document expects {step['code']}"
                )
        sys.stdout.flush()


def run_document(path: Path, tmp: Path) -> tuple[int, str]:
    """Run one document's steps in a child process under ``tmp``; the exit code and output."""
    plan = steps(path)
    if not any(step["kind"] in ("python", "sh") for step in plan):
        return 0, "nothing to run"
    work, bindir = tmp / "work", tmp / "bin"
    work.mkdir()
    bindir.mkdir()
    rheolin = bindir / "rheolin"
    rheolin.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m rheolin.cli "$@"\n')
    rheolin.chmod(0o755)
    (tmp / "plan.json").write_text(json.dumps(plan))
    env = dict(
        os.environ,
        PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT / "src"), os.environ.get("PYTHONPATH")])),
        MPLBACKEND="Agg",
        OPENBLAS_NUM_THREADS="1",
        OMP_NUM_THREADS="1",
        MKL_NUM_THREADS="1",
        COLUMNS="100",
    )
    proc = subprocess.Popen(
        [sys.executable, __file__, str(tmp / "plan.json"), str(rheolin)],
        cwd=work,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )
    try:
        output, _ = proc.communicate(timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        output, _ = proc.communicate()
        return -1, f"{output}\n{path.name}: timed out after {TIMEOUT:.0f} s"
    finally:
        try:  # Dask workers and anything else the document started
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    return proc.returncode, output


@pytest.mark.parametrize("path", DOCS, ids=lambda p: p.name)
def test_every_block_runs(path: Path, tmp_path: Path) -> None:
    """The document's blocks run as written (python, commands) or parse (TOML)."""
    code, output = run_document(path, tmp_path)
    assert code == 0, textwrap.shorten(output, 100_000) if code != 0 else ""


@pytest.mark.parametrize("comment", ["", "  # exit code 2"])
def test_an_unexpected_exit_code_fails_the_document(comment: str, tmp_path: Path) -> None:
    """``rheolin validate missing.toml`` exits 2 (no such file): its document fails, unless
    the line's comment says ``exit code 2``; its message reaches the output either way."""
    doc = tmp_path / "doc.md"
    doc.write_text(f"```console\n$ rheolin validate missing.toml{comment}\n```\n")
    (tmp_path / "doc").mkdir()
    code, output = run_document(doc, tmp_path / "doc")
    assert "missing.toml" in output.partition("$ rheolin validate missing.toml")[2], output
    if comment:
        assert code == 0, output
    else:
        assert code == 1 and "doc.md:2: `rheolin validate missing.toml` exited 2," in output


# ---------------------------------------------------------------- names in the prose

SPAN = re.compile(r"(?<!`)`([^`\n]+)`(?!`)")
DOTTED = re.compile(r"\b(rheolin(?:\.[A-Za-z_]\w*)+|rl\.[A-Za-z_]\w*|Model\.[A-Za-z_]\w*)")
MISSING = object()
PATHS = re.compile(r"\b((?:src|tests|bench|docs)/[\w./-]+\.(?:py|md|png|toml))(?:::(\w+))?")


def prose(path: Path) -> str:
    """A document without its fenced blocks."""
    text = path.read_text(encoding="utf-8")
    return re.sub(r"^\s*```.*?^\s*```\s*$", "", text, flags=re.M | re.S)


def resolve(name: str) -> Any:
    """The object a dotted name gives (a module, or attributes of one: class attributes and
    dataclass fields included), or ``MISSING``."""
    import rheolin
    from rheolin.mechanics import Model

    head, *rest = name.split(".")
    if head == "rl":
        obj: Any = rheolin
    elif head == "Model":
        obj = Model
    else:
        obj, k = None, len(rest)
        while k >= 0 and obj is None:
            try:
                obj = importlib.import_module(".".join([head, *rest[:k]]))
            except ModuleNotFoundError:
                k -= 1
        rest = rest[k:]
    for part in rest:
        fields = getattr(obj, "__dataclass_fields__", {})
        if part in fields and not hasattr(obj, part):
            return fields[part]  # a dataclass field without a default: on instances only
        if not hasattr(obj, part):
            return MISSING
        obj = getattr(obj, part)
    return obj


def keywords_missing(obj: Any, args: str) -> list[str]:
    """The ``name=`` keywords of a call written in the prose that ``obj`` does not take."""
    try:
        params = inspect.signature(obj).parameters
    except (TypeError, ValueError):
        return []
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values()):
        return []
    return [k for k in re.findall(r"\b([a-z_]\w*)=", args) if k not in params]


def test_every_api_name_in_the_prose_exists() -> None:
    """``rheolin.x.y``, ``rl.x`` and ``Model.x`` in inline code resolve, and the keywords of
    a call written there (``rl.solve(..., sparse_backend=)``) are parameters of it."""
    missing = []
    for path in DOCS:
        for span in SPAN.findall(prose(path)):
            for m in DOTTED.finditer(span):
                obj = resolve(m.group(1))
                if obj is MISSING:
                    missing.append(f"{path.name}: {m.group(1)}")
                    continue
                call = re.match(r"\(([^)]*)\)?", span[m.end() :])
                if call:
                    bad = keywords_missing(obj, call.group(1))
                    missing += [f"{path.name}: {m.group(1)} takes no {k}=" for k in bad]
    assert not missing, "names the docs give that do not exist:\n" + "\n".join(missing)


def cli_options() -> dict[str, set[str]]:
    """Every command of the CLI and the options it takes (the group's options included)."""
    import typer.main

    from rheolin.cli import app

    group = typer.main.get_command(app)
    common = {o for p in group.params for o in (*p.opts, *p.secondary_opts)}
    return {
        name: common | {o for p in cmd.params for o in (*p.opts, *p.secondary_opts)}
        for name, cmd in group.commands.items()  # type: ignore[attr-defined]
    }


def test_every_command_and_option_in_the_docs_exists() -> None:
    """``rheolin <command> --option`` in prose and in shell blocks: the command and each
    option exist (the blocks also run; the prose is checked here only)."""
    known = cli_options()
    bad = []
    for path in DOCS:
        texts = SPAN.findall(prose(path))
        texts += [c for b in blocks(path) if b.lang in ("console", "sh") for _, c, _ in commands(b)]
        for text in texts:
            for m in re.finditer(r"(?:^|[\s(])rheolin((?:\s+[^\s`|>]+)*)", text):
                words = shlex.split(m.group(1).replace("'", " "), posix=False)
                words = [w for w in words if w != "--debug"]
                if not words or words[0].startswith("-") or not re.match(r"^[a-z-]+$", words[0]):
                    continue
                if words[0] not in known:
                    bad.append(f"{path.name}: no command `rheolin {words[0]}`")
                    continue
                for w in words[1:]:
                    opt = w.split("=")[0]
                    if opt.startswith("--") and opt not in known[words[0]]:
                        bad.append(f"{path.name}: `rheolin {words[0]}` has no option {opt}")
    assert not bad, "\n".join(bad)


def test_every_file_link_and_test_named_in_the_docs_exists() -> None:
    """Paths in the text (``tests/...py::test_name`` included) and relative Markdown links."""
    bad = []
    for path in DOCS:
        text = path.read_text(encoding="utf-8")
        for rel, test in PATHS.findall(text):
            target = ROOT / rel.rstrip(".")
            if not target.exists():
                bad.append(f"{path.name}: {rel} does not exist")
            elif test:
                names = {
                    n.name
                    for n in ast.walk(ast.parse(target.read_text(encoding="utf-8")))
                    if isinstance(n, ast.FunctionDef)
                }
                if test not in names:
                    bad.append(f"{path.name}: {rel} has no {test}")
        for link, anchor in re.findall(r"\]\(([^)#\s]*)(?:#([^)\s]*))?\)", text):
            if re.match(r"^[a-z]+:", link):
                continue
            target = path.parent / link if link else path
            if not target.exists():
                bad.append(f"{path.name}: link {link} does not resolve")
            elif anchor and target.suffix == ".md" and anchor not in anchors(target):
                bad.append(f"{path.name}: {link or path.name} has no heading #{anchor}")
    assert not bad, "\n".join(bad)


def anchors(path: Path) -> set[str]:
    """GitHub's anchors of a Markdown file's headings: lower case, punctuation dropped,
    spaces to hyphens."""
    out = set()
    for heading in re.findall(r"^#+\s+(.*?)\s*$", prose(path), flags=re.M):
        out.add(re.sub(r"[^\w\- ]", "", heading.lower()).replace(" ", "-"))
    return out


if __name__ == "__main__":  # the child process of run_document
    driver(json.loads(Path(sys.argv[1]).read_text()), sys.argv[2])
