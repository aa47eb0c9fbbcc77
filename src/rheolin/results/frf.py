"""Frequency response functions at a fixed speed: non-synchronous excitation, Bode data.

A force ``F cos(w t)`` at one DOF, with ``w`` unrelated to the speed (a blade pass, a
hydraulic pulsation, a shaker), drives a time-periodic system at ``w`` *and* at the sidebands
``w + h w1`` of the coefficient harmonics ``h``: with ``q(t) = Re sum_h q_h exp(i (w + h w1) t)``
the harmonic balance is the Hill operator of the stability analysis at ``lambda = i w``,

    sum_n ( K_{m-n} + s_n D_{m-n} + s_n^2 M_{m-n} ) q_n = F delta_{m0},   s_n = i (w + n w1),

over the harmonic lattice of the coefficient harmonics (:mod:`~rheolin.harmonics.lattice`,
order ``p``; docs/stability.md). ``q_0`` per unit force is the receptance ``H(w)``; the
``q_h`` are its sidebands. A time-invariant system (an axisymmetric rotor at constant speed)
has the lattice ``{0}`` and the classical ``H(w) = (K - w^2 M + i w (D + W G))^-1``.

>>> import numpy as np, rheolin as rl
>>> s = rl.PeriodicSystem(1.0, M={0: np.eye(1)}, D={0: 0.2 * np.eye(1)}, K={0: 4 * np.eye(1)})
>>> frf = system_frequency_response(s, [2.0], inputs=[0])
>>> complex(frf.receptance[0, 0, 0])  # 1 / (4 - 4 + 0.4 i)
-2.5j
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..budget import MemoryBudgetError, format_bytes, memory_budget
from ..errors import ModelError
from ..harmonics.hill_lattice import LatticeHill
from ..harmonics.lattice import Lattice, harmonic_lattice, system_lattice
from ..harmonics.sets import TruncationWarning
from ..linalg.direct import analyze, resolve_backend
from ..system.periodic import PeriodicSystem

__all__ = [
    "FrequencyResponse",
    "frequency_response",
    "parse_dof",
    "receptance_unit",
    "system_frequency_response",
]

#: The lattice order of a time-periodic system's FRF (as for its stability).
DEFAULT_ORDER = 2

#: A response with more than this fraction of its norm on the lattice's outer shell is
#: reported as possibly truncated (a warning; raise ``order``).
BOUNDARY_WARN = 1e-3

COMPONENTS = ("ux", "uy", "uz", "phix", "phiy", "phiz")


def receptance_unit(output: str, inp: str, unbalance: bool = False) -> str:
    """The unit of a receptance from DOF ``inp`` to DOF ``output`` (labels
    ``body:node:component``; a bare index counts as a translation): ``m/N``, ``rad/N``,
    ``m/(N m)``, ``rad/(N m)``, or per kg m of unbalance.

    >>> receptance_unit("r:1:ux", "r:1:ux"), receptance_unit("r:1:phiz", "r:0:phiz")
    ('m/N', 'rad/(N m)')
    >>> receptance_unit("r:1:uy", "r:1:ux", unbalance=True)
    'm/(kg m)'
    """
    top = "rad" if str(output).rsplit(":", 1)[-1].startswith("phi") else "m"
    if unbalance:
        return f"{top}/(kg m)"
    return f"{top}/(N m)" if str(inp).rsplit(":", 1)[-1].startswith("phi") else f"{top}/N"


@dataclass
class FrequencyResponse:
    """Receptances and their sidebands over excitation frequencies.

    Attributes
    ----------
    frequencies
        Excitation frequencies ``w`` [rad/s], shape ``(n_f,)``.
    sidebands
        Lattice harmonics ``h`` (response frequency ``w + h w1``), shape ``(n_h,)``, 0 included.
    response
        ``q_h`` per unit input, shape ``(n_f, n_h, n_out, n_in)`` [m/N, rad/N, m/(N m) or
        rad/(N m); per unit unbalance ``m e`` (kg m) with ``unbalance=True``].
    inputs, outputs
        DOF labels (``"body:node:component"``) or indices.
    omega
        Base frequency ``w1`` [rad/s] of the system.
    speed
        Input speed [rad/s] (NaN for a bare system).
    unbalance
        The inputs are rotating-unbalance-like forces ``m e w^2`` per unit ``m e``.
    info
        ``lattice_order``, ``boundary_fraction`` (the largest share of a response on the
        lattice's outer shell), ``singular`` (frequencies where ``Q(i w)`` is singular: NaN).
    """

    frequencies: np.ndarray
    sidebands: np.ndarray
    response: np.ndarray
    inputs: list[str]
    outputs: list[str]
    omega: float
    speed: float = float("nan")
    unbalance: bool = False
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def receptance(self) -> np.ndarray:
        """``q_0`` per unit input, at the excitation frequency: ``(n_f, n_out, n_in)``."""
        return self.response[:, int(np.flatnonzero(self.sidebands == 0)[0])]

    @classmethod
    def from_dataset(cls, ds: Any) -> FrequencyResponse:
        """The response read back from :meth:`to_dataset` (``frf.nc``).

        >>> import numpy as np, rheolin as rl
        >>> s = rl.PeriodicSystem(1.0, M={0: np.eye(1)}, K={0: 4 * np.eye(1)})
        >>> r = system_frequency_response(s, [1.0, 3.0], inputs=[0])
        >>> back = FrequencyResponse.from_dataset(r.to_dataset())
        >>> bool(np.allclose(back.receptance, r.receptance)), back.inputs
        (True, ['0'])
        """

        def joined(da: Any) -> np.ndarray:
            return np.asarray(da.sel(part="real").values + 1j * da.sel(part="imag").values)

        attrs = ds.attrs
        return cls(
            frequencies=np.asarray(ds["frequency"].values, dtype=float) * 2 * np.pi,
            sidebands=np.asarray(ds["sideband"].values, dtype=np.int64),
            response=joined(ds["sideband_response"]),
            inputs=[str(v) for v in ds["input"].values],
            outputs=[str(v) for v in ds["output"].values],
            omega=float(attrs.get("base_frequency_rad_s", float("nan"))),
            speed=float(attrs.get("speed_rad_s", float("nan"))),
            unbalance=bool(attrs.get("unbalance", 0)),
            info={
                "lattice_order": int(attrs.get("lattice_order", 0)),
                "boundary_fraction": float(attrs.get("boundary_fraction", 0.0)),
            },
        )

    def to_dataset(self) -> Any:
        """The FRF as an ``xarray.Dataset`` (complex values on a trailing ``part`` axis).

        >>> import numpy as np, rheolin as rl
        >>> s = rl.PeriodicSystem(1.0, M={0: np.eye(1)}, K={0: 4 * np.eye(1)})
        >>> ds = system_frequency_response(s, [1.0, 3.0], inputs=[0]).to_dataset()
        >>> ds["receptance"].dims
        ('frequency', 'output', 'input', 'part')
        """
        import xarray as xr

        from .units import significant

        def parts(z: np.ndarray) -> np.ndarray:
            return np.stack([z.real, z.imag], axis=-1)

        hz = self.frequencies / (2 * np.pi)
        units = np.array(
            [[receptance_unit(o, i, self.unbalance) for i in self.inputs] for o in self.outputs],
            dtype=str,
        )
        unit = (
            str(units.flat[0])
            if len(set(units.flat)) == 1
            else "per output and input: receptance_units"
        )
        return xr.Dataset(
            {
                "receptance": (
                    ("frequency", "output", "input", "part"),
                    parts(self.receptance),
                    {"units": unit, "long_name": "response at the excitation frequency"},
                ),
                "sideband_response": (
                    ("frequency", "sideband", "output", "input", "part"),
                    parts(self.response),
                    {"units": unit, "long_name": "response at w + h w1 (h = sideband)"},
                ),
                "receptance_units": (("output", "input"), units, {"units": "1"}),
            },
            coords={
                "frequency": ("frequency", hz, {"units": "Hz"}),
                "sideband": ("sideband", self.sidebands.astype(np.int64), {"units": "1"}),
                "sideband_offset": (
                    "sideband",
                    self.sidebands * self.omega / (2 * np.pi),
                    {"units": "Hz"},
                ),
                "output": ("output", list(self.outputs)),
                "input": ("input", list(self.inputs)),
                "part": ("part", ["real", "imag"]),
            },
            attrs={
                "speed_rad_s": float(self.speed),
                "speed_rpm": significant(float(self.speed) * 30 / np.pi),
                "base_frequency_rad_s": float(self.omega),
                "unbalance": int(self.unbalance),
                "lattice_order": int(self.info.get("lattice_order", 0)),
                "boundary_fraction": float(self.info.get("boundary_fraction", 0.0)),
                "convention": "response to F cos(w t): Re sum_h q_h exp(i (w + h w1) t)",
            },
        )


def _solve(analysis: Any, Q: sp.csc_array, rhs: np.ndarray) -> np.ndarray | None:
    """``Q^-1 rhs`` through the shared analysis, checked by its residual (SuperLU from scratch
    when the factor is off); None when ``Q`` is singular."""
    Q.sort_indices()
    scale = float(spla.norm(Q, 1))
    for attempt in range(2):
        try:
            if attempt == 0:
                x = np.asarray(analysis.factor(Q.data).solve(rhs))
            else:
                x = np.asarray(spla.splu(Q).solve(rhs))
        except (RuntimeError, ValueError, np.linalg.LinAlgError):
            continue
        if not np.all(np.isfinite(x)):
            continue
        res = float(np.linalg.norm(Q @ x - rhs)) / max(scale * float(np.linalg.norm(x)), 1e-300)
        if res <= 1e-10:
            return x
    return None


def parse_dof(text: str | tuple[str, int, str], labels: Sequence[tuple[str, int, str]]) -> int:
    """The global DOF of ``"body:node:component"`` (or a tuple) among ``labels``.

    >>> parse_dof("rotor:1:uy", [("rotor", 1, "ux"), ("rotor", 1, "uy")])
    1
    """
    if isinstance(text, str):
        parts = text.split(":")
        if len(parts) != 3:
            raise ModelError(
                f"DOF {text!r}: write it as body:node:component, e.g. rotor:3:ux "
                f"(components {', '.join(COMPONENTS)})"
            )
        body, node_text, comp = (p.strip() for p in parts)
        try:
            node = int(node_text)
        except ValueError:
            raise ModelError(
                f"DOF {text!r}: the node must be an integer, got {node_text!r}"
            ) from None
    else:
        body, node, comp = text
    if comp not in COMPONENTS:
        raise ModelError(f"DOF {text!r}: the component must be one of {list(COMPONENTS)}")
    index = {lab: i for i, lab in enumerate(labels)}
    key = (body, int(node), comp)
    if key not in index:
        bodies = sorted({b for b, _, _ in labels})
        if body not in bodies:
            raise ModelError(f"DOF {text!r}: no body {body!r} (bodies: {', '.join(bodies)})")
        nodes = sorted({n for b, n, _ in labels if b == body})
        raise ModelError(
            f"DOF {text!r}: body {body!r} has no node {node} with {comp} "
            f"(nodes {nodes[0]}..{nodes[-1]})"
        )
    return index[key]


def frequency_response(
    model: Any,
    speed: float,
    frequencies: Sequence[float] | np.ndarray,
    inputs: Sequence[str | tuple[str, int, str]],
    outputs: Sequence[str | tuple[str, int, str]] | None = None,
    *,
    order: int | None = None,
    unbalance: bool = False,
    budget: Any = None,
    progress: Callable[[int], None] | None = None,
) -> FrequencyResponse:
    """FRF of ``model`` turning at ``speed`` [rad/s], over excitation ``frequencies`` [rad/s].

    ``inputs``/``outputs``: DOFs as ``"body:node:component"`` (``ux uy uz phix phiy phiz``;
    outputs default to the inputs). A unit force (or moment) at each input in turn, at each
    frequency; ``unbalance=True`` scales it by ``w^2`` (the force of a unit ``m e`` turning at
    ``w``). ``order``: the lattice order for a time-periodic model (default 2). See the module
    docstring for the convention. ``progress(done)`` is called after each frequency.

    >>> import numpy as np, rheolin as rl
    >>> m = rl.Model()
    >>> m.add_shaft("s", [0.0, 0.5], outer_diameter=0.05, material="steel")
    >>> m.add_disk("s", 1, outer_diameter=0.3, width=0.05, material="steel")
    >>> m.add_bearing("b", "s", 0, stiffness=1e7, damping=100.0)
    >>> frf = frequency_response(m, 100.0, [10.0, 20.0], inputs=["s:1:ux"])
    >>> frf.receptance.shape
    (2, 1, 1)
    """
    assembled = model.assemble(float(speed))
    labels = assembled.dof_labels
    inp = [parse_dof(x, labels) for x in inputs]
    out = inp if outputs is None else [parse_dof(x, labels) for x in outputs]

    def name(x: str | tuple[str, int, str]) -> str:
        return x if isinstance(x, str) else f"{x[0]}:{x[1]}:{x[2]}"

    res = system_frequency_response(
        assembled.system,
        frequencies,
        inp,
        out,
        order=order,
        unbalance=unbalance,
        budget=budget,
        progress=progress,
    )
    res.inputs = [name(x) for x in inputs]
    res.outputs = res.inputs if outputs is None else [name(x) for x in outputs]
    res.speed = float(speed)
    return res


def system_frequency_response(
    system: PeriodicSystem,
    frequencies: Sequence[float] | np.ndarray,
    inputs: Sequence[int],
    outputs: Sequence[int] | None = None,
    *,
    order: int | None = None,
    unbalance: bool = False,
    budget: Any = None,
    progress: Callable[[int], None] | None = None,
) -> FrequencyResponse:
    """:func:`frequency_response` of a :class:`~rheolin.PeriodicSystem` (DOFs by index)."""
    w = np.atleast_1d(np.asarray(frequencies, dtype=float))
    if w.ndim != 1 or w.size == 0 or not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ModelError("frequencies: need one or more finite excitation frequencies >= 0")
    n = system.n
    inp = np.asarray(inputs, dtype=np.int64)
    out = inp if outputs is None else np.asarray(outputs, dtype=np.int64)
    for what, idx in (("inputs", inp), ("outputs", out)):
        if idx.size == 0 or idx.min() < 0 or idx.max() >= n:
            raise ModelError(f"{what}: need DOF indices in 0..{n - 1}")
    p = DEFAULT_ORDER if order is None else int(order)
    if p < 0:
        raise ModelError(f"order: must be >= 0, got {order}")
    # inputs and outputs through the rigid links (eliminated): f_r = T^T f, q = T y
    if system.constraint is not None:
        T = system.constraint.transform()
        system = system.constraint.reduce(system)
        n = system.n
        B_in = np.asarray(T.T.toarray()[:, inp], dtype=complex)
        C_out = T.toarray()[out, :]
    else:
        B_in = np.eye(n, dtype=complex)[:, inp]
        C_out = np.eye(n)[out, :]
    if system.time_invariant:
        lat: Lattice = harmonic_lattice({}, 0)
    else:
        lat = system_lattice(system, p, max_size=10**6)
    hill = LatticeHill(system, lat.indices)
    need = hill.memory_bytes()
    limit = memory_budget(budget)
    if need > limit:
        raise MemoryBudgetError(
            f"the FRF's lattice operator ({len(lat)} harmonics x {n} DOFs) needs an estimated "
            f"{format_bytes(need)}, more than the memory budget of {format_bytes(limit)}: "
            "lower the lattice order"
        )
    nh = lat.indices.size
    i0 = lat.position(0)
    rhs = np.zeros((n * nh, inp.size), dtype=complex)
    rhs[i0 * n : (i0 + 1) * n] = B_in  # the inputs act at the excitation frequency
    boundary = lat.boundary
    resp = np.full((w.size, nh, out.size, inp.size), np.nan + 0j)
    worst = 0.0
    singular: list[float] = []
    pattern = hill.Q(1j)
    pattern.sort_indices()
    name = resolve_backend("auto", (pattern.indptr, pattern.indices, pattern.shape[0]))
    analysis = analyze(name, pattern.indptr, pattern.indices, True, sample=pattern.data)
    for i, wi in enumerate(w):
        if progress is not None:
            progress(i)
        Q = hill.Q(1j * wi)  # the same pattern at every frequency: one symbolic analysis
        x = _solve(analysis, Q, rhs)
        if x is None:  # singular: an undamped resonance, or a free body at 0
            singular.append(float(wi))
            continue
        if nh > 1 and np.any(boundary):
            blocks = np.abs(x.reshape(nh, n, inp.size)) ** 2
            per = blocks.sum(axis=1)
            total = per.sum(axis=0)
            worst = max(worst, float(np.max(per[boundary].sum(axis=0) / np.maximum(total, 1e-300))))
        scale = wi * wi if unbalance else 1.0
        resp[i] = scale * np.einsum("oj,hji->hoi", C_out, x.reshape(nh, n, inp.size))
    if progress is not None:
        progress(w.size)
    info: dict[str, Any] = {
        "sparse_backend": name,
        "lattice_order": lat.order,
        "lattice_size": nh,
        "boundary_fraction": worst,
        "singular": singular,
    }
    if worst > BOUNDARY_WARN:
        warnings.warn(
            f"the FRF holds up to {worst:.2g} of its norm on the outer shell of the lattice of "
            f"order {lat.order} ({nh} harmonics): its sidebands may be truncated; raise the "
            "order",
            TruncationWarning,
            stacklevel=2,
        )
    return FrequencyResponse(
        frequencies=w,
        sidebands=lat.indices.copy(),
        response=resp,
        inputs=[str(int(i)) for i in inp],
        outputs=[str(int(i)) for i in out],
        omega=float(system.omega),
        unbalance=unbalance,
        info=info,
    )
