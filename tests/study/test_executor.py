"""The local executors of maps and studies: forked workers (copies of this process, one BLAS
thread each) and the fall-back to a local Dask cluster where forking is not safe."""

from __future__ import annotations

import os
import threading

import pytest

from rheolin.study.executor import DaskExecutor, ForkExecutor, fork_safe, local_workers


def _where(_: object) -> tuple[int, list[int]]:
    from threadpoolctl import threadpool_info

    return os.getpid(), [int(p["num_threads"]) for p in threadpool_info()]


def _fails(_: object) -> None:
    raise ValueError("a task's own error")


def test_forked_workers_run_tasks_with_one_blas_thread() -> None:
    """Tasks run in other processes, each limited to one BLAS thread although the parent's
    BLAS runs two when it forks them (a copy keeps the parent's count: the environment is read
    when the library loads), and a task's error comes back as that error, the other tasks'
    results unaffected."""
    from threadpoolctl import threadpool_info, threadpool_limits

    with threadpool_limits(2):
        assert any(int(p["num_threads"]) == 2 for p in threadpool_info())
        ex = ForkExecutor(2)
    try:
        handles = [ex.submit(_where, i) for i in range(4)]
        bad = ex.submit(_fails, None)
        got = {}
        while len(got) < 5:
            assert ex.ready(timeout=30.0)
            handle, out, error = ex.next_done()
            got[handle] = (out, error)
    finally:
        ex.close()
    for h in handles:
        (pid, threads), error = got[h]
        assert error is None
        assert pid != os.getpid()
        assert threads and all(t == 1 for t in threads), threads
    out, error = got[bad]
    assert out is None and isinstance(error, ValueError) and "own error" in str(error)


def test_no_fork_while_another_thread_runs() -> None:
    """With a second thread alive the process is not forked (a lock that thread holds would
    stay locked in the copy): the workers are a local Dask cluster."""
    stop = threading.Event()
    thread = threading.Thread(target=stop.wait, daemon=True)
    thread.start()
    try:
        assert not fork_safe()
        with local_workers(1) as ex:
            assert isinstance(ex, DaskExecutor)
            ex.submit(_where, 0)
            _, (pid, _), error = ex.next_done()
            assert error is None and pid != os.getpid()
    finally:
        stop.set()
        thread.join()


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork on this platform")
def test_fork_executor_closes_its_running_workers() -> None:
    """Closing the executor ends a worker still running a task (Ctrl-C, or another task's
    error), instead of waiting for it."""
    import time

    ex = ForkExecutor(1)
    ex.submit(time.sleep, 60.0)
    t0 = time.monotonic()
    ex.close()
    assert time.monotonic() - t0 < 10.0


def test_workers_end_quietly_under_a_commands_sigterm_handler(
    capfd: pytest.CaptureFixture[str],
) -> None:
    """A command forks its workers inside its SIGTERM handler (SIGTERM ends the command like
    Ctrl-C); the workers must not keep that handler: closing the pool, with idle workers and
    with a running one, prints nothing (each used to print a KeyboardInterrupt traceback)."""
    import time

    from rheolin.cli.errors import sigterm_as_interrupt

    with sigterm_as_interrupt():
        ex = ForkExecutor(2)
        try:
            h = ex.submit(_where, None)
            assert ex.ready(timeout=30.0)
            assert ex.next_done()[0] == h
        finally:
            ex.close()
        ex = ForkExecutor(1)
        ex.submit(time.sleep, 60.0)
        time.sleep(0.5)  # the task is running
        t0 = time.monotonic()
        ex.close()
        assert time.monotonic() - t0 < 10.0
    err = capfd.readouterr().err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
