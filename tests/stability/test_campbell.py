"""Campbell diagram against the closed-form gyroscopic split of an overhung disk.

A rigid disk (mass ``m``, transverse and polar inertia ``J_t``, ``J_p``) at the tip of a
massless Timoshenko cantilever of length ``L``, clamped through a bearing of stiffness ``k_b``
on every component. Tip flexibility for a tip force ``P`` and moment ``M`` in one bending
plane (deflection ``u``, slope ``theta``), with the clamp compliance ``1 / k_b`` in
translation and rotation::

    u     = P (L^3 / 3EI + L / kappa G A + 1/k_b + L^2/k_b) + M (L^2 / 2EI + L/k_b)
    theta = P (L^2 / 2EI + L/k_b)                            + M (L / EI + 1/k_b)

``K = F^-1``. Circular whirl ``u_x + i u_y = U e^{i w t}`` at spin ``W`` (gyroscopic moment
``J_p W`` times the tilt rate): forward whirl satisfies
``det([[k11 - m w^2, k12], [k12, k22 - J_t w^2 + J_p W w]]) = 0`` and backward whirl the same
with ``-J_p W w``: the forward frequencies rise with speed, the backward ones fall.
"""

from __future__ import annotations

import numpy as np
import pytest

from rheolin.mechanics import Model
from rheolin.mechanics.sections import solid_circular
from rheolin.stability import campbell

E, NU, D, L, KB = 2.1e11, 0.3, 0.03, 0.25, 1e12
M, JT, JP = 8.0, 0.04, 0.07


def _overhung() -> Model:
    model = Model()
    model.add_shaft(
        "rotor", [0.0, L], outer_diameter=D, elastic_modulus=E, poisson_ratio=NU, density=0.0
    )
    model.add_disk("rotor", 1, mass=M, inertia=(JT, JT, JP))
    model.add_bearing("clamp", "rotor", 0, KB, components=None)
    return model


def _tip_stiffness() -> np.ndarray:
    sec = solid_circular(D, NU)
    EI, GA = E * sec.Iy, E / (2 * (1 + NU)) * sec.kappa_y * sec.area
    F = np.array(
        [
            [L**3 / (3 * EI) + L / GA + 1 / KB + L**2 / KB, L**2 / (2 * EI) + L / KB],
            [L**2 / (2 * EI) + L / KB, L / EI + 1 / KB],
        ]
    )
    return np.linalg.inv(F)


def _whirl_frequencies(W: float, sign: int) -> np.ndarray:
    """Positive roots of the forward (sign=+1) / backward (-1) characteristic quartic."""
    (k11, k12), (_, k22) = _tip_stiffness()
    # (k11 - m w^2)(k22 - Jt w^2 + s Jp W w) - k12^2
    poly = np.polymul([-M, 0.0, k11], [-JT, sign * JP * W, k22])
    poly = np.polysub(poly, [k12**2])
    r = np.roots(poly)
    return np.sort(r.real[(np.abs(r.imag) < 1e-9 * np.abs(r)) & (r.real > 0)])


def test_forward_and_backward_whirl_against_gyroscopic_split() -> None:
    speeds = np.array([50.0, 500.0, 1500.0, 3000.0])
    res = campbell(_overhung(), speeds)
    for i, W in enumerate(speeds):
        labels = res.whirl[i]
        for sign, kind in ((+1, "forward"), (-1, "backward")):
            got = np.sort(res.frequency[i][labels == kind])
            ref = _whirl_frequencies(W, sign)
            assert got.size == 2, (W, kind, res.frequency[i], labels)
            np.testing.assert_allclose(got, ref, rtol=1e-8)
        # axial and torsional modes of the disk on the shaft: no whirl
        assert set(labels[(labels != "forward") & (labels != "backward")]) <= {"none"}
    # the gyroscopic split grows with speed: forward up, backward down
    fwd = [np.sort(res.frequency[i][res.whirl[i] == "forward"])[1] for i in range(4)]
    bwd = [np.sort(res.frequency[i][res.whirl[i] == "backward"])[1] for i in range(4)]
    assert np.all(np.diff(fwd) > 0) and np.all(np.diff(bwd) < 0)
    assert np.allclose(res.damping_ratio[np.isfinite(res.damping_ratio)], 0.0, atol=1e-9)


def test_critical_speeds_are_order_line_crossings() -> None:
    """The 1x forward crossing solves the forward quartic with ``w = W``:
    ``(k11 - m W^2)(k22 - (J_t - J_p) W^2) = k12^2``."""
    (k11, k12), (_, k22) = _tip_stiffness()
    x = np.roots(np.polysub(np.polymul([-M, k11], [JP - JT, k22]), [k12**2]))
    ref = np.sqrt(x.real[(x.real > 0) & (np.abs(x.imag) < 1e-9)])
    speeds = np.linspace(0.8, 1.2, 9) * ref.min()
    res = campbell(_overhung(), speeds)
    crit = [c for c in res.critical_speeds if c.order == "1x rotor" and c.whirl == "forward"]
    assert len(crit) == 1
    # linear interpolation between samples 5 % apart: second-order error
    assert crit[0].speed == pytest.approx(ref.min(), rel=2e-3)
    ds = res.to_dataset()
    assert "critical_speed" in ds and ds.sizes["speed"] == speeds.size


def test_standstill_modes_are_the_non_spinning_closed_form() -> None:
    """W = 0 is allowed: forward and backward whirl coincide there, each lateral frequency
    twice, the roots of the quartic without the gyroscopic term; the CLI takes 0:...rpm."""
    res = campbell(_overhung(), np.array([0.0, 500.0]))
    assert res.speeds[0] == 0.0
    f0 = res.frequency[0][np.isfinite(res.frequency[0])]
    for ref in _whirl_frequencies(0.0, +1):
        assert np.sum(np.abs(f0 / ref - 1) < 1e-8) == 2, (ref, f0)
    with pytest.raises(ValueError, match=">= 0"):
        campbell(_overhung(), np.array([-1.0, 500.0]))
    from rheolin._cli_report import parse_speeds

    assert parse_speeds("0:1000:500rpm", allow_zero=True)[0] == 0.0
