"""``solve``: one entry point over the registered methods, one result type."""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import numpy as np

from ..budget import MemoryBudgetError, format_bytes, memory_budget
from ..floquet import Continuation, dense_stability_harmonics, floquet, floquet_memory
from ..floquet.result import NUMERICAL_FAILURES
from ..harmonics.balance import HarmonicBalance, SingularBlockError
from ..harmonics.sets import HarmonicSet, as_harmonic_set
from ..system.periodic import PeriodicSystem
from ..system.rigid_modes import RigidModes
from ..system.rigid_modes import held_rigid_modes as find_rigid_modes
from . import direct, krylov, lti, perturbation, transient  # noqa: F401  (register the methods)
from .arguments import check_arguments, check_loads, check_size
from .registry import METHODS, RESIDUAL_CHECKED, Options, SolverOutcome
from .solution import Solution

__all__ = ["solve", "stability_harmonics"]

log = logging.getLogger(__name__)

#: Iterative methods may land slightly above ``rtol`` when the recurrence residual and the
#: recomputed one differ by round-off; beyond this factor the result is not a success.
_ROUNDOFF_SLACK = 2.0
#: Below this a recomputed residual is round-off whatever ``rtol`` asks.
_RESIDUAL_FLOOR = 1e-12


def solve(
    system: PeriodicSystem,
    harmonics: HarmonicSet | int | Iterable[int],
    *,
    method: str = "auto",
    rtol: float = 1e-10,
    maxiter: int | None = None,
    callback: Callable[[int, float], None] | None = None,
    workers: int | None = None,
    stability: bool | None = None,
    options: Mapping[str, Any] | None = None,
    x0: Solution | np.ndarray | None = None,
    backend: str = "auto",
    sparse_backend: str = "auto",
    memory_budget: str | int | None = None,
    continuation: Continuation | None = None,
) -> Solution:
    """Periodic steady state of ``M(t) q'' + D(t) q' + K(t) q = f(t)`` by harmonic balance.

    Parameters
    ----------
    system
        The periodic system.
    harmonics
        The harmonic set: an int ``N`` (``-N..N``), an iterable of ints, or a
        :class:`~rheolin.HarmonicSet`.
    method
        ``"auto"``, ``"lti"``, ``"perturbation"``, ``"gmres"``, ``"direct"`` (docs/solvers.md),
        or ``"transient"`` (BDF time integration from rest until periodic: the baseline).
    rtol
        Tolerance of the iterative methods on ``||f - A q|| / ||f||``, and the acceptance
        criterion of every result on the backward error ``||f - A q|| / (||A|| ||q|| +
        ||f||)`` (:meth:`~rheolin.harmonics.balance.HarmonicBalance.backward_error`, reported as
        ``Solution.residual``; the relative residual is ``info["relative_residual"]``).
        See docs/solvers.md.
    maxiter
        Iteration cap (default 200 for perturbation, 500 for gmres).
    callback
        Called as ``callback(iteration, relative_residual)`` by iterative methods.
    workers
        Threads for the per-harmonic SuperLU factorizations and solves, from one long-lived
        pool (default 1: SuperLU holds the GIL, so threads rarely pay; see
        :mod:`rheolin.linalg.pool`).
    stability
        Check Floquet stability (Hill's method, :func:`rheolin.floquet` with its automatic
        choice of truncation) of the operating point. ``None`` (default) checks whenever the
        estimated memory of the Hill problem fits the memory budget
        (:func:`rheolin.budget.memory_budget`) and says in ``message`` why when it does
        not; ``True`` always (raises :class:`~rheolin.budget.MemoryBudgetError` beyond the
        budget); ``False`` never. An unstable operating point gives ``success=False``,
        ``status=4``: its periodic solution exists but is not physical (docs/stability.md). The
        Floquet result is kept in ``Solution.floquet``.
    continuation
        Over a sweep, the :class:`~rheolin.floquet.Continuation` shared by the solves at
        successive speeds: each stability check's lattice searches start from the previous
        one's eigenvectors.
    options
        Method-specific options (e.g. for ``"transient"``), passed through unchanged.
    x0
        Initial guess for the iterative methods: a :class:`~rheolin.Solution` (e.g. at a
        neighbouring speed of a sweep; matched by harmonic index, missing ones are zero) or
        coefficients over ``harmonics`` (shape ``(len(harmonics), n)``).
    backend
        Inverse of the time-averaged blocks ``A0(n)``: ``"auto"`` (by size), ``"lu"``
        (sparse LU per harmonic), ``"dense"`` (batched dense LU, small systems) or
        ``"modal"`` (one eigendecomposition for every harmonic; falls back to ``"lu"`` when
        its accuracy check fails). See :mod:`rheolin.linalg`.
    sparse_backend
        Sparse direct solver behind ``"lu"``: ``"auto"`` (the fastest installed: MKL
        PARDISO, then UMFPACK via kvxopt, then SciPy's SuperLU), or one of those by name
        (:mod:`rheolin.linalg.direct`).
    memory_budget
        What the solve may use (bytes or ``"8 GB"``); default ``RHEOLIN_SOLVE_MEMORY``, else
        most of the memory available (:func:`rheolin.budget.solve_budget`). The estimate is
        checked before allocating (:class:`~rheolin.budget.MemoryBudgetError` with the
        estimate and what to change); factors beyond it are refactorized on demand.

    Returns
    -------
    Solution
        ``success`` is False, with a ``message``, when the method did not converge.

    Examples
    --------
    A Jeffcott rotor with a stiffness asymmetry, under unbalance:

    >>> import numpy as np, rheolin as rl
    >>> W = 0.5; K2 = 0.1 * np.array([[1, -1j], [-1j, -1]]) / 2
    >>> s = rl.PeriodicSystem(W, M={0: np.eye(2)}, D={0: 0.02 * np.eye(2)},
    ...                       K={0: np.eye(2), 2: K2}, f={1: np.array([1, -1j]) * W**2 / 2})
    >>> sol = rl.solve(s, 5, method="gmres")
    >>> sol.success, sol.method, bool(sol.residual < 1e-10), sol.stable
    (True, 'gmres', True, True)
    """
    if not isinstance(system, PeriodicSystem):
        raise TypeError(f"`system` must be a PeriodicSystem, got {type(system).__name__}")
    check_arguments(maxiter, method, memory_budget, backend, sparse_backend)
    check_size(system, harmonics, memory_budget)  # before the set is even built
    hset = as_harmonic_set(harmonics)
    check_loads(system, hset, warn=not isinstance(harmonics, HarmonicSet))
    if not (isinstance(rtol, int | float) and 0.0 < rtol < 1.0):
        raise ValueError(f"`rtol` must be a number in (0, 1), got {rtol!r}")
    if maxiter is not None and (isinstance(maxiter, bool) or int(maxiter) < 1):
        raise ValueError(f"`maxiter` must be a positive integer, got {maxiter!r}")
    allowed = ["auto", *METHODS]
    if method not in allowed:
        raise ValueError(f"`method` must be one of {allowed}, got {method!r}")
    again = dict(
        method=method, rtol=rtol, maxiter=maxiter, callback=callback, workers=workers,
        stability=stability, options=options, backend=backend, sparse_backend=sparse_backend,
        memory_budget=memory_budget, continuation=continuation,
    )  # fmt: skip
    if system.constraint is not None:  # rigid links: eliminated, the answer on every DOF
        return _linked(system, hset, x0, again)
    # rigid-body modes: looked for once harmonic 0 turns out singular (the factorization of
    # A0(0) = K_0 says so at no cost); `direct` factorizes the coupled matrix instead, which
    # the modes' coupling can leave regular, so it looks first
    if method == "direct":
        rigid = find_rigid_modes(system)
        if rigid is not None:
            return _constrained(system, rigid, hset, x0, again)
    opts = Options(rtol=float(rtol), maxiter=maxiter, callback=callback, extra=dict(options or {}))
    op = HarmonicBalance(
        system,
        hset,
        workers=workers,
        backend=backend,
        sparse_backend=sparse_backend,
        memory_budget=memory_budget,
    )
    opts.x0 = _initial_guess(op, x0)
    found: list[RigidModes | None] = []  # looked for at most once

    def rigid_modes() -> RigidModes | None:
        if not found:
            found.append(find_rigid_modes(system))
        return found[0]

    if method == "auto":
        sol = _auto(op, opts, rigid_modes)
    else:
        sol = _finish(op, _run(method, op, opts), opts)
    if not sol.success and sol.info.get("singular_harmonic") == 0:
        rigid = rigid_modes()
        if rigid is not None:
            return _constrained(system, rigid, hset, x0, again)
    return _check_stability(system, sol, stability, continuation)


def _constrained(
    system: PeriodicSystem,
    rigid: RigidModes,
    hset: HarmonicSet,
    x0: Solution | np.ndarray | None,
    kwargs: dict[str, Any],
) -> Solution:
    """Solve with the rigid-body modes held (:mod:`rheolin.system.rigid_modes`); the result is on
    every DOF of ``system``."""
    sol = _reduced(rigid, system, hset, x0, kwargs)
    sol.message = f"{rigid.note(system)}; {sol.message}"
    sol.info["rigid_modes"] = rigid.count
    sol.info["rigid_dominant_dofs"] = rigid.dominant_dofs(system)
    sol.info["rigid_mean_load"] = [float(x) for x in rigid.mean_load(system)]
    return sol


def _linked(
    system: PeriodicSystem,
    hset: HarmonicSet,
    x0: Solution | np.ndarray | None,
    kwargs: dict[str, Any],
) -> Solution:
    """Solve with the system's exact constraints eliminated (:mod:`rheolin.system.constraints`);
    the result is on every DOF of ``system``."""
    c = system.constraint
    sol = _reduced(c, system, hset, x0, kwargs)
    sol.info["constrained_dofs"] = int(c.pivots.size)
    return sol


def _reduced(
    c: Any,
    system: PeriodicSystem,
    hset: HarmonicSet,
    x0: Solution | np.ndarray | None,
    kwargs: dict[str, Any],
) -> Solution:
    """Solve the system reduced by the constraint ``c`` (a warm start restricted to its kept
    DOFs) and expand the solution to every DOF."""
    if isinstance(x0, Solution):
        x0 = dataclasses.replace(x0, q=c.restrict(x0.q))
    elif x0 is not None:
        x0 = c.restrict(np.asarray(x0))
    sol = solve(c.reduce(system), hset, x0=x0, **kwargs)
    sol.q = c.expand(sol.q)
    return sol


def _initial_guess(op: HarmonicBalance, x0: Solution | np.ndarray | None) -> np.ndarray | None:
    """The half ``n >= 0`` of an initial guess, on the operator's harmonics."""
    if x0 is None:
        return None
    if isinstance(x0, Solution):
        out = np.zeros_like(op.rhs)
        if x0.q.shape[1] != op.n_dof:
            raise ValueError(f"`x0` has {x0.q.shape[1]} DOFs, the system {op.n_dof}")
        where = {int(n): i for i, n in enumerate(x0.harmonics)}
        for i, n in enumerate(op.pos):
            if int(n) in where:
                out[i] = x0.q[where[int(n)]]
        return out
    try:
        arr = np.asarray(x0, dtype=complex)
    except (TypeError, ValueError):
        raise ValueError(
            f"`x0` must be a Solution or an array of coefficients, got {x0!r:.80}"
        ) from None
    if arr.shape != (op.full.size, op.n_dof):
        raise ValueError(
            f"`x0` must have shape ({op.full.size}, {op.n_dof}) (harmonics x DOFs), got {arr.shape}"
        )
    return op.half(arr)


def stability_harmonics(system: PeriodicSystem) -> HarmonicSet:
    """Dense Hill truncation for a stability check (see :func:`~rheolin.floquet.floquet`)."""
    return dense_stability_harmonics(system)


def _check_stability(
    system: PeriodicSystem,
    sol: Solution,
    stability: bool | None,
    continuation: Continuation | None = None,
) -> Solution:
    if stability is False:
        return sol
    if stability is None:
        kind, estimate = floquet_memory(system)
        limit = memory_budget()
        if estimate > limit:
            sol.message += (
                f"; stability not checked: the {kind} Hill problem needs an estimated "
                f"{format_bytes(estimate)}, more than the memory budget of "
                f"{format_bytes(limit)} (raise RHEOLIN_MEMORY_BUDGET, or reduce the model)"
            )
            return sol
    try:
        res = floquet(system, continuation=continuation)
    except MemoryBudgetError as exc:
        if stability:  # asked for explicitly: the caller refuses with the estimate
            raise
        sol.message += f"; stability not checked: {exc}"
        return sol
    except NUMERICAL_FAILURES as exc:
        # a numerical failure of the check (a factorization, an eigensolver that did not
        # converge) leaves the verdict open; the solve itself stands
        sol.message += f"; stability not checked: {exc}"
        sol.info["stability_error"] = f"{type(exc).__name__}: {exc}"
        return sol
    sol.floquet = res
    sol.stable, sol.max_floquet_real = res.stable, res.max_real
    if not res.decided:
        size = res.info.get("size", 0) // max(2 * system.n, 1)
        what = (
            f"the lattice of order {res.lattice.order} ({len(res.lattice)} harmonics)"
            if res.lattice is not None
            else f"the Hill truncation ({size} harmonics)"
        )
        band = res.info.get("band") or {}
        if band and not band.get("certified", True):
            sol.message += f"; stability undecided: {band.get('reason')}"
        else:
            sol.message += (
                f"; {what} did not converge for every Floquet exponent: the stability verdict "
                "is uncertain"
            )
    if not res.stable and sol.success:
        sol.success, sol.status = False, 4
        sol.message += (
            f"; but the operating point is unstable (largest Floquet real part "
            f"{res.max_real:.3g} 1/s > 0): the periodic solution is not physical"
        )
    return sol


def _run(method: str, op: HarmonicBalance, opts: Options) -> SolverOutcome:
    if op.rhs_norm == 0.0:
        return SolverOutcome(np.zeros_like(op.rhs), True, 0, "zero load: q = 0", method)
    try:
        return METHODS[method](op, opts)
    except SingularBlockError as exc:
        out = SolverOutcome(
            np.zeros_like(op.rhs),
            False,
            3,
            f"{exc}: the time-averaged system is singular at harmonic {exc.n} "
            f"({'a free motion or ' if exc.n == 0 else ''}an undamped resonance); a "
            "preconditioned method cannot run",
            method,
        )
        out.info["singular_harmonic"] = int(exc.n)
        return out


def _finish(op: HarmonicBalance, out: SolverOutcome, opts: Options, note: str = "") -> Solution:
    computed = out.status != 3 or out.Q.any()
    relative = op.relative_residual(out.Q) if computed else float("nan")
    residual = op.backward_error(out.Q) if computed else float("nan")
    success, status, message = out.converged, out.status, out.message
    limit = max(_ROUNDOFF_SLACK * opts.rtol, _RESIDUAL_FLOOR)
    if success and out.method in RESIDUAL_CHECKED and not residual <= limit:
        success, status = False, (1 if out.method in ("gmres", "perturbation") else 3)
        message = (
            f"{message}, but the recomputed backward error {residual:.3g} exceeds rtol "
            f"{opts.rtol:.3g}"
        )
    elif not success and out.status in (1, 3) and computed and residual <= opts.rtol:
        # e.g. stiff ties: ||f - A q|| / ||f|| stalls at round-off times ||A|| ||q|| / ||f||
        success, status = True, 0
        message = (
            f"{message}; but the backward error {residual:.3g} is within rtol {opts.rtol:.3g} "
            f"(relative residual ||f - A q|| / ||f|| = {relative:.3g}, dominated by round-off "
            "in a stiff model): accepted"
        )
    if note:
        message = f"{note}; {message}"
    if not success:
        log.warning("%s: %s", out.method, message)
    info = dict(out.info)
    info["relative_residual"] = float(relative)
    info["memory_estimate"] = op.memory.total
    store = op.factor_store
    if store is not None:
        info["sparse_backend"] = store.name
        info["refactorizations"] = store.refactorizations
    if op.backend_note:
        info["backend_note"] = op.backend_note
    return Solution(
        harmonics=op.full.copy(),
        q=op.expand(out.Q),
        omega=op.w1,
        success=bool(success),
        status=int(status),
        message=message,
        method=out.method,
        iterations=out.iterations,
        history=list(out.history),
        residual=float(residual),
        info=info,
    )


def _auto(
    op: HarmonicBalance, opts: Options, rigid_modes: Callable[[], RigidModes | None]
) -> Solution:
    """``lti`` for a time-invariant system; else ``gmres``, falling back to ``direct``."""
    if not op.system.coefficient_harmonics:
        return _finish(op, _run("lti", op, opts), opts, "auto chose lti (time-invariant)")
    first = _finish(op, _run("gmres", op, opts), opts, "auto chose gmres")
    if first.success:
        return first
    if first.info.get("singular_harmonic") == 0 and rigid_modes() is not None:
        return first  # solve() holds the rigid-body modes and solves again
    fallback = _finish(
        op,
        _run("direct", op, opts),
        opts,
        f"auto: gmres failed ({first.message}); fell back to direct",
    )
    if fallback.success:
        return fallback
    first.message = fallback.message  # it says why gmres failed, then why direct did
    return first
