"""The data of a model: its bodies and tables, the checks of names and nodes, and
:func:`recorded`, which keeps every ``add_*`` call for the model file.

:class:`ModelData` is what the assembly (:mod:`~rheolin.mechanics.template`) and the operating
point (:mod:`~rheolin.mechanics.preload`) read; :class:`~rheolin.mechanics.model.Model` adds
the vocabulary that fills it.

>>> import numpy as np
>>> from fractions import Fraction
>>> b = Body("r", "rigid", np.array([0.0, 0.0, 1.0]), np.zeros((1, 3)), Fraction(1))
>>> ModelData.node(b, 0), b.kind
(0, 'rigid')
"""

from __future__ import annotations

import functools
import inspect
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Any, ParamSpec, TypeVar

import numpy as np

from ..errors import ModelError

if TYPE_CHECKING:
    from .rigid import RigidNode

__all__ = ["Body", "ModelData", "positive", "recorded"]

_P = ParamSpec("_P")
_R = TypeVar("_R")


def recorded(method: Callable[_P, _R]) -> Callable[_P, _R]:
    """Record a successful ``add_*`` call (its explicit arguments) in ``model.calls``: the
    model file is these calls one to one (:meth:`~rheolin.mechanics.model.Model.to_toml`)."""
    sig = inspect.signature(method)

    @functools.wraps(method)
    def wrapper(*args: _P.args, **kwargs: _P.kwargs) -> _R:
        out = method(*args, **kwargs)
        bound = sig.bind(*args, **kwargs).arguments
        model = bound.pop("self")
        model.calls.append((method.__name__, dict(bound)))
        return out

    return wrapper


def positive(x: Any, name: str) -> float:
    """``x`` as a positive finite float, else a :class:`~rheolin.errors.ModelError` naming
    ``name``."""
    try:
        v = float(x)
    except (TypeError, ValueError):
        raise ModelError(f"`{name}` must be a positive number, got {x!r}") from None
    if not np.isfinite(v) or v <= 0:
        raise ModelError(f"`{name}` must be a positive finite number, got {x!r}")
    return v


@dataclass
class Body:
    """A body of the model: its nodes along its spin axis, and what each kind needs."""

    name: str
    kind: str  # "shaft" | "rigid" | "condensed"
    axis: np.ndarray
    positions: np.ndarray  # (n_nodes, 3)
    speed_ratio: Fraction | None
    data: dict[str, Any] = field(default_factory=dict)
    disks: dict[int, RigidNode] = field(default_factory=dict)


class ModelData(ABC):
    """The tables of a model (bodies, joints, meshes, loads, links) and their name/node checks.

    Parameters
    ----------
    input_body
        Body whose speed is the input speed; default: the first body.
    unbalance_reference
        The global direction that is angle 0 of every unbalance; default x (y for bodies
        turning about x).
    """

    def __init__(
        self, input_body: str | None = None, unbalance_reference: Sequence[float] | None = None
    ) -> None:
        self.input_body = input_body
        self.unbalance_reference = (
            None if unbalance_reference is None else tuple(float(v) for v in unbalance_reference)
        )
        ref = np.asarray(self.unbalance_reference or (1.0, 0.0, 0.0), dtype=float)
        if ref.shape != (3,) or not np.all(np.isfinite(ref)) or not np.any(ref):
            raise ModelError(
                f"`unbalance_reference` must be a nonzero 3-vector, got {unbalance_reference!r}"
            )
        self.bodies: dict[str, Body] = {}
        self.joints: dict[str, dict[str, Any]] = {}
        self.meshes: dict[str, dict[str, Any]] = {}
        self.forces: dict[str, dict[str, Any]] = {}
        self.links: dict[str, dict[str, Any]] = {}
        #: load-dependent joints and applied torques (operating point: mechanics.preload)
        self.rolling: dict[str, dict[str, Any]] = {}
        self.torques: dict[str, dict[str, Any]] = {}
        self.gravity: np.ndarray | None = None
        #: ``(method, arguments)`` of every ``add_*``/``set_gravity`` call, in order.
        self.calls: list[tuple[str, dict[str, Any]]] = []

    @property
    def preloaded(self) -> bool:
        """True when the model declares torques or load-dependent joints: it is solved about
        its operating point (:meth:`operating_point`)."""
        return bool(self.rolling or self.torques) or any(
            g.get("load_law") is not None for g in self.meshes.values()
        )

    @abstractmethod
    def operating_point(self, speed: float) -> Any:
        """The static equilibrium at input ``speed`` [rad/s], cached by the model that
        solves it (:meth:`rheolin.mechanics.model.Model.operating_point`)."""

    # ------------------------------------------------------------------ checks
    def new_body(self, name: str, field_name: str = "name") -> None:
        """Refuse a body name that is empty or taken."""
        if not isinstance(name, str) or not name:
            raise ModelError(f"`{field_name}` must be a non-empty string, got {name!r}")
        if name in self.bodies:
            raise ModelError(f"`{field_name}`: a body named {name!r} already exists")

    def body(self, name: str, field_name: str) -> Body:
        """The body ``name``, or an error naming ``field_name`` and the bodies there are."""
        if name not in self.bodies:
            raise ModelError(f"`{field_name}`: no body named {name!r}; bodies: {list(self.bodies)}")
        return self.bodies[name]

    @staticmethod
    def node(b: Body, node: Any) -> int:
        """``node`` as an index of one of ``b``'s nodes."""
        if (
            isinstance(node, bool)
            or not isinstance(node, int | np.integer)
            or not (0 <= node < len(b.positions))
        ):
            raise ModelError(
                f"`node` must be an integer in [0, {len(b.positions)}) for body "
                f"{b.name!r}, got {node!r}"
            )
        return int(node)

    @staticmethod
    def new_item(name: str, table: dict[str, Any]) -> None:
        """Refuse an item name that is empty or taken in ``table``."""
        if not isinstance(name, str) or not name:
            raise ModelError(f"`name` must be a non-empty string, got {name!r}")
        if name in table:
            raise ModelError(f"`name`: {name!r} is already used")

    def joint_nodes(
        self, name: str, body: str, node: int, other_body: str | None, other_node: int | None
    ) -> None:
        """Check a new joint's name (linear and load-dependent joints share the names) and
        nodes (``other_*``: the other side, or ground)."""
        self.new_item(name, self.joints)
        self.new_item(name, self.rolling)
        self.node(self.body(body, "body"), node)
        if (other_body is None) != (other_node is None):
            raise ModelError("`other_body` and `other_node` must be given together")
        if other_body is not None:
            self.node(self.body(other_body, "other_body"), other_node)
