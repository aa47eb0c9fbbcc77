"""Small models for the study tests, with closed-form answers."""

from __future__ import annotations

import numpy as np

from rheolin.mechanics import Model

#: A rigid rotor on a spring fixed in its own axes (k_x != k_y), no damping in its plane:
#: unstable exactly between sqrt(k_x / m) and sqrt(k_y / m) (m = 1 kg).
BAND = """
[model]
name = "rigid rotor on a spring fixed in its own axes"
input_body = "r"

[[rigid_bodies]]
name = "r"
position = "0 0 0 m"
mass = "1 kg"
inertia = ["1 kg*m^2", "1 kg*m^2", "1 kg*m^2"]

[[rigid_bodies.disks]]
node = 0
unbalance = "1e-6 kg*m"
unbalance_angle = "30 deg"

[[rigid_bodies.bearings]]
name = "spring"
node = 0
components = ["ux", "uy"]
stiffness = ["1e4 N/m", "1.21e4 N/m"]
damping = ["0 N*s/m", "0 N*s/m"]
frame = "r"

[[rigid_bodies.bearings]]
name = "ground"
node = 0
components = ["uz", "phix", "phiy", "phiz"]
stiffness = ["1e4 N/m", "1e4 N*m/rad", "1e4 N*m/rad", "1e4 N*m/rad"]
damping = ["1 N*s/m", "1 N*m*s/rad", "1 N*m*s/rad", "1 N*m*s/rad"]
"""


def band_model(ky: float = 1.21e4, cx: float = 0.0) -> Model:
    """``BAND`` written with the Python API (SI units), spring stiffness ``k_y``, damping
    ``c_x`` of the spring in x: an independent way to the model a parameter study builds."""
    m = Model(input_body="r")
    m.add_rigid_body("r", (0.0, 0.0, 0.0), 1.0, (1.0, 1.0, 1.0))
    m.add_disk("r", 0, unbalance=1e-6, unbalance_angle=np.radians(30.0))
    m.add_bearing("spring", "r", 0, [1e4, ky], [cx, 0.0], ("ux", "uy"), frame="r")
    m.add_bearing(
        "ground", "r", 0, [1e4, 1e4, 1e4, 1e4], [1.0, 1.0, 1.0, 1.0], ("uz", "phix", "phiy", "phiz")
    )
    return m


def rpm(x: float) -> float:
    """rpm -> rad/s."""
    return x * np.pi / 30


def ctrl_c_reaches_python() -> None:
    """``preexec_fn`` of a child that must take Ctrl-C: SIGINT back to its default, so that
    Python turns it into KeyboardInterrupt. A run started in the background of a
    non-interactive shell (a CI script's ``cmd &``) inherits SIGINT ignored, and Python then
    leaves it ignored: both Ctrl-C tests failed that way on a clean clone."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)
