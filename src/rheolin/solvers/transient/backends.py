"""Integrator backends of the transient baseline: SciPy BDF and SUNDIALS IDA (optional)."""

from __future__ import annotations

import logging
import warnings
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp

from .settings import DENSE_JAC_MAX

if TYPE_CHECKING:
    from .model import Coefficients, Detector, Series
    from .settings import TransientSettings

__all__ = ["run_scipy", "run_sundae"]

log = logging.getLogger(__name__)


def run_scipy(c: Coefficients, s: TransientSettings, det: Detector) -> dict[str, Any]:
    from scipy.integrate import BDF

    n = c.n
    minv = c.mass_inverse()

    def fun(t: float, y: np.ndarray) -> np.ndarray:
        f = c.refresh(t)
        q, v = y[:n], y[n:]
        return np.concatenate([v, minv.solve(f - c.D.matvec(v) - c.K.matvec(q))])

    def jac(t: float, y: np.ndarray) -> Any:
        c.refresh(t)
        K, D = c.K.matrix(), c.D.matrix()
        KD = np.hstack([K, D]) if c.dense else sp.hstack([K, D], format="csc").toarray()
        X = -minv.solve(KD)
        if 2 * n <= DENSE_JAC_MAX or np.count_nonzero(X) > 0.1 * X.size:
            J = np.zeros((2 * n, 2 * n))
            J[:n, n:] = np.eye(n)
            J[n:] = X
            return J
        eye = sp.identity(n, format="csr")
        return sp.bmat([[None, eye], [sp.csr_array(X), None]], format="csc")

    t_bound = (s.max_periods + 0.5) * s.period
    solver = BDF(
        fun, 0.0, np.zeros(2 * n), t_bound, rtol=s.rtol, atol=s.atol, jac=jac, max_step=s.max_step
    )
    steps = 0
    det.take(np.zeros((1, n)))  # the state at t = 0 (at rest)
    while not det.done and det.periods < s.max_periods:
        msg = solver.step()
        steps += 1
        if solver.status == "failed":
            return {"failed": f"BDF failed at t = {solver.t:.6g} s: {msg}", "steps": steps}
        ts = det.pending(solver.t)
        while ts.size:
            det.take(solver.dense_output()(ts)[:n].T)
            if det.done or det.periods >= s.max_periods:
                break
            ts = det.pending(solver.t)
    return {"steps": steps, "nfev": solver.nfev, "njev": solver.njev, "nlu": solver.nlu}


def run_sundae(c: Coefficients, s: TransientSettings, det: Detector) -> dict[str, Any]:
    from sksundae.ida import IDA

    n = c.n
    N = 2 * n
    eye = sp.identity(n, format="coo")
    # sparsity of J = dF/dy + cj dF/dy' = [[cj I, -I], [K, D + cj M]]
    parts: list[tuple[np.ndarray, np.ndarray]] = [
        (eye.row, eye.col),
        (eye.row, eye.col + n),
    ]
    blocks: list[tuple[Series, int]] = [(c.K, 0), (c.D, n), (c.M, n)]
    consts = [
        sp.coo_array((n, n)) if series.const is None else sp.coo_array(series.const)
        for series, _ in blocks
    ]
    for (series, off), coo in zip(blocks, consts, strict=True):
        parts.append((coo.row + n, coo.col + off))
        parts.append((series.rows + n, series.cols + off))
    rows = np.concatenate([p[0] for p in parts]).astype(np.int64)
    cols = np.concatenate([p[1] for p in parts]).astype(np.int64)
    keys = np.unique(cols * N + rows)  # CSC order: by column, then row
    pattern = sp.csc_array((np.ones(keys.size), (keys % N, keys // N)), shape=(N, N))
    pattern.indices = pattern.indices.astype(np.int32)  # SUNDIALS' index type
    pattern.indptr = pattern.indptr.astype(np.int32)

    def positions(r: np.ndarray, cc: np.ndarray) -> np.ndarray:
        return np.searchsorted(keys, cc.astype(np.int64) * N + r.astype(np.int64))

    base_a = np.zeros(keys.size)  # constant part of dF/dy
    base_b = np.zeros(keys.size)  # constant part of dF/dy' (times cj)
    base_b[positions(eye.row, eye.col)] += 1.0
    base_a[positions(eye.row, eye.col + n)] -= 1.0
    var_pos = {}
    for name, (series, off), coo in zip("KDM", blocks, consts, strict=True):
        target = base_b if name == "M" else base_a
        np.add.at(target, positions(coo.row + n, coo.col + off), coo.data)
        if series.varies:
            var_pos[name] = positions(series.rows + n, series.cols + off)

    def resfn(t: float, y: np.ndarray, yp: np.ndarray, res: np.ndarray) -> None:
        f = c.refresh(t)
        q, v = y[:n], y[n:]
        res[:n] = yp[:n] - v
        res[n:] = c.M.matvec(yp[n:]) + c.D.matvec(v) + c.K.matvec(q) - f

    def jacfn(
        t: float, y: np.ndarray, yp: np.ndarray, res: np.ndarray, cj: float, JJ: np.ndarray
    ) -> None:
        b = c.basis(t)
        out = base_a + cj * base_b
        for name, series in (("K", c.K), ("D", c.D), ("M", c.M)):
            if name in var_pos:
                data = series.refresh(b)
                out[var_pos[name]] += cj * data if name == "M" else data
        JJ[:] = out

    with warnings.catch_warnings():  # "custom sparse Jacobian ignored": jacfn is exact
        warnings.simplefilter("ignore", UserWarning)
        solver = IDA(
            resfn,
            jacfn=jacfn,
            sparsity=pattern,
            linsolver="sparse",
            rtol=s.rtol,
            atol=s.atol,
            max_step=s.max_step,
            max_num_steps=100000,
        )
    f0 = c.refresh(0.0)
    yp0 = np.concatenate([np.zeros(n), c.mass_inverse().solve(f0)])
    init = solver.init_step(0.0, np.zeros(N), yp0)
    if not init.success:
        return {"failed": f"IDA could not start: {init.message}", "steps": 0}
    t_bound = (s.max_periods + 0.5) * s.period
    steps = 0
    det.take(np.zeros((1, n)))
    while not det.done and det.periods < s.max_periods:
        r = solver.step(t_bound, method="onestep")
        steps += 1
        if not r.success:
            return {
                "failed": f"IDA failed at t = {float(r.t[-1]):.6g} s: {r.message}",
                "steps": steps,
            }
        t_now = float(np.atleast_1d(r.t)[-1])
        ts = det.pending(t_now)
        while ts.size:
            ys = []
            for tk in ts:
                rk = solver.step(float(tk))
                ys.append(np.atleast_2d(rk.y)[-1, :n])
            det.take(np.array(ys))
            if det.done or det.periods >= s.max_periods:
                break
            ts = det.pending(t_now)
    return {"steps": steps, "nfev": int(getattr(r, "nfev", 0)) if steps else 0}
