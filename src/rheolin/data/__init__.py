"""Built-in example model files (TOML), shipped as package data.

>>> sorted(EXAMPLES)
['gearbox', 'preloaded', 'rotor', 'wind-turbine']
>>> example_text("rotor").startswith("#")
True
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["EXAMPLES", "example_path", "example_text"]

#: Example names and one-line descriptions.
EXAMPLES = {
    "gearbox": "two-stage spur gearbox, hunting-tooth ratios, unbalance, a shaft with a flat",
    "rotor": "small asymmetric Jeffcott-type rotor on anisotropic bearings (fast, Floquet-checked)",
    "preloaded": "spur gear pair under torque: Hertzian ball/roller bearings, ISO 6336 mesh "
    "stiffness, solved about its static equilibrium",
    "wind-turbine": "750 kW wind-turbine drive train (NREL GRC gearing): rotor, main shaft, a "
    "three-planet stage, two helical stages, generator",
}


def example_path(name: str = "gearbox") -> Path:
    """Path of a built-in example file."""
    if name not in EXAMPLES:
        raise KeyError(f"no example named {name!r}; examples: {sorted(EXAMPLES)}")
    return Path(str(resources.files(__name__).joinpath(f"{name}.toml")))


def example_text(name: str = "gearbox") -> str:
    """Text of a built-in example file."""
    return example_path(name).read_text(encoding="utf-8")
