"""The report's interactive figures (plotly): zoom, hover for values, click a legend entry
to hide a curve. Each function takes the result files' data and returns a
``plotly.graph_objects.Figure``; the units are those of the plots (rpm, Hz, µm, N).

>>> import numpy as np, xarray as xr
>>> sds = xr.Dataset({"max_real": ("speed", [-2.0, -1.0]), "tol": ("speed", [0.1, 0.1]),
...                   "stable": ("speed", [True, True]), "decided": ("speed", [True, True])},
...                  coords={"speed": [100.0, 200.0]})
>>> len(stability_figure(sds).data)
2
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np
import plotly.graph_objects as go
import xarray as xr
from plotly.subplots import make_subplots

from ..plots._common import length_unit, shown_harmonics
from ..plots.point import bearing_amplitudes, default_nodes, radial_amplitude

__all__ = [
    "bearing_figure",
    "bode_figure",
    "campbell_figure",
    "orbit_figure",
    "spectrum_figure",
    "stability_figure",
    "sweep_figure",
    "waterfall_figure",
]

RPM = 30 / math.pi
HZ = 1 / (2 * math.pi)
LAYOUT = dict(template="plotly_white", height=460, margin=dict(l=70, r=30, t=60, b=60))
PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2")
WHIRL_SCALE = [[0.0, "#d62728"], [0.5, "#f7f7f7"], [1.0, "#1f77b4"]]


def _stems(x: np.ndarray, y: np.ndarray, floor: float) -> tuple[list[Any], list[Any]]:
    """Vertical segments from ``floor`` to each ``y`` as one line trace (None separated)."""
    xs: list[Any] = []
    ys: list[Any] = []
    for a, b in zip(x, y, strict=True):
        xs += [a, a, None]
        ys += [floor, b, None]
    return xs, ys


def _markers(fig: go.Figure, ds: xr.Dataset, lo: float, hi: float, y: tuple[float, float]) -> None:
    """Shaft speeds and mesh frequencies within ``[lo, hi]`` as dashed vertical lines from
    ``y[0]`` to ``y[1]``, named at the top (traces: they follow log axes, unlike shapes)."""
    marks = [
        (k, f) for k, f in json.loads(ds.attrs.get("markers_json", "{}")).items() if lo <= f <= hi
    ]
    for group, colour in (("mesh", "#d62728"), ("shaft", "#777777")):
        chosen = [(k, f) for k, f in marks if ("mesh" in k) == (group == "mesh")]
        if not chosen:
            continue
        xs: list[Any] = []
        ys: list[Any] = []
        for _, f in chosen:
            xs += [f, f, None]
            ys += [y[0], y[1], None]
        name = "mesh frequencies" if group == "mesh" else "shaft speeds"
        fig.add_trace(
            go.Scatter(
                x=xs,
                y=ys,
                mode="lines",
                name=name,
                hoverinfo="skip",
                line=dict(dash="dash", width=1, color=colour),
            )
        )
        fig.add_trace(
            go.Scatter(
                x=[f for _, f in chosen],
                y=[y[1]] * len(chosen),
                mode="text",
                text=[k for k, _ in chosen],
                textposition="top center",
                showlegend=False,
                textfont=dict(color=colour, size=10),
                hoverinfo="skip",
            )
        )


def spectrum_figure(ds: xr.Dataset) -> go.Figure:
    """Radial amplitude 2|q_n| [µm] against frequency at each body's most responsive node."""
    fig = go.Figure()
    r = radial_amplitude(ds)
    f = ds["frequency"].values
    osc = ds["harmonic"].values > 0
    nodes = default_nodes(ds)
    top = float(max(r.sel(node=nodes).values[osc].max(initial=0.0) * 1e6, 1e-12))
    for i, node in enumerate(nodes):
        amp = r.sel(node=node).values[osc] * 1e6
        keep = shown_harmonics(amp, top)
        colour = PALETTE[i % len(PALETTE)]
        xs, ys = _stems(f[osc][keep], amp[keep], top * 1e-4)
        fig.add_trace(
            go.Scatter(
                x=xs,
                y=ys,
                mode="lines",
                line=dict(width=1, color=colour),
                legendgroup=node,
                showlegend=False,
                hoverinfo="skip",
                name=node,
            )
        )
        fig.add_trace(
            go.Scatter(
                x=f[osc][keep],
                y=amp[keep],
                mode="markers",
                name=node,
                legendgroup=node,
                marker=dict(color=colour),
                customdata=ds["order"].values[osc][keep],
                hovertemplate="%{x:.4g} Hz (order %{customdata:.4g})<br>%{y:.3g} µm",
            )
        )
    lo = float(f[osc][f[osc] > 0].min(initial=1.0))
    _markers(fig, ds, lo, float(f.max()), (top * 1e-4, top * 1.5))
    fig.update_xaxes(type="log", title="frequency [Hz]")
    fig.update_yaxes(type="log", title="radial amplitude 2|q_n| [µm]")
    fig.update_layout(title="response spectrum (harmonics within 60 dB)", **LAYOUT)
    return fig


def orbit_figure(ds: xr.Dataset) -> go.Figure:
    """Each body's most responsive node: its orbit over one revolution of its shaft, about
    the static position."""
    nodes = default_nodes(ds)
    fig = make_subplots(rows=1, cols=len(nodes), subplot_titles=nodes)
    q = ds["displacement"].sel(component=["ux", "uy"])
    n = ds["harmonic"].values.astype(float)
    w1 = float(ds.attrs["base_frequency"])
    markers = json.loads(ds.attrs.get("markers_json", "{}"))
    for k, node in enumerate(nodes, start=1):
        body = str(ds["body"].sel(node=node).values)
        period = 1.0 / markers.get(f"{body} 1x", w1 / (2 * math.pi))
        t = np.linspace(0.0, period, 2000)
        c = q.sel(node=node, part="real").values + 1j * q.sel(node=node, part="imag").values
        c = c * np.where(n > 0, 2.0, 1.0)[:, None]
        osc = n > 0
        xy = (np.exp(1j * w1 * np.outer(t, n[osc])) @ c[osc]).real
        unit, scale = length_unit(float(np.abs(xy).max(initial=0.0)))
        fig.add_trace(
            go.Scatter(
                x=xy[:, 0] * scale,
                y=xy[:, 1] * scale,
                mode="lines",
                name=f"{node} [{unit}]",
                hovertemplate=f"ux %{{x:.3g}} {unit}<br>uy %{{y:.3g}} {unit}",
            ),
            row=1,
            col=k,
        )
        fig.update_xaxes(title=f"ux - static [{unit}]", row=1, col=k)
        fig.update_yaxes(
            title=f"uy - static [{unit}]", scaleanchor=f"x{k if k > 1 else ''}", row=1, col=k
        )
    fig.update_layout(title="orbits over one shaft revolution (dynamic part)", **LAYOUT)
    return fig


def bearing_figure(ds: xr.Dataset) -> go.Figure:
    """The dynamic load of every bearing (the largest kind it carries) against frequency."""
    fig = go.Figure()
    f = ds["frequency"].values[ds["harmonic"].values > 0]
    for b in [str(x) for x in ds["bearing"].values]:
        found = bearing_amplitudes(ds, b)
        if not found:
            continue
        quantity, unit, amp = found[0]
        keep = shown_harmonics(amp)
        fig.add_trace(
            go.Scatter(
                x=f[keep],
                y=amp[keep],
                mode="markers",
                name=f"{b} ({quantity})",
                hovertemplate=f"%{{x:.4g}} Hz<br>%{{y:.3g}} {unit}",
            )
        )
    fig.update_xaxes(type="log", title="frequency [Hz]")
    fig.update_yaxes(type="log", title="amplitude [N, N m]")
    fig.update_layout(title="bearing loads (click a bearing to hide it)", **LAYOUT)
    return fig


def sweep_figure(ds: xr.Dataset, resonances: list[dict[str, Any]], ranges: list[Any]) -> go.Figure:
    """The largest radial response per body against speed; resonance peaks with their AF;
    unstable ranges shaded."""
    fig = go.Figure()
    rpm = ds["speed_rpm"].values
    resp = ds["response"].where(ds["harmonic"] > 0, 0.0)
    for body in dict.fromkeys(ds["body"].values.tolist()):
        y = resp.where(ds["body"] == body, drop=True).sum("harmonic").max("node").values * 1e6
        fig.add_trace(
            go.Scatter(
                x=rpm,
                y=y,
                mode="lines+markers",
                name=str(body),
                hovertemplate="%{x:.6g} rpm<br>%{y:.3g} µm",
            )
        )
    if resonances:
        fig.add_trace(
            go.Scatter(
                x=[p["speed_rpm"] for p in resonances],
                y=[p["amplitude_m"] * 1e6 for p in resonances],
                mode="markers",
                marker=dict(symbol="triangle-down", size=12, color="black"),
                name="resonance peak",
                text=[f"{p['body']}: AF {_af(p)}" for p in resonances],
                hovertemplate="%{x:.6g} rpm, %{y:.3g} µm<br>%{text}",
            )
        )
    for lo, hi in ranges:
        fig.add_vrect(x0=lo, x1=hi, fillcolor="red", opacity=0.15, line_width=0)
    fig.update_xaxes(title="input speed [rpm]")
    fig.update_yaxes(type="log", title="radial dynamic response (sum of harmonics) [µm]")
    fig.update_layout(title="response against speed", **LAYOUT)
    return fig


def _af(p: dict[str, Any]) -> str:
    af = p.get("amplification_factor")
    return "n/a" if af is None else f"{af:.3g}"


def waterfall_figure(ds: xr.Dataset) -> go.Figure:
    """Frequency against speed at the most responsive node, colour = amplitude (log)."""
    resp = ds["response"].where(ds["harmonic"] > 0, 0.0)
    node = str(resp.sum("harmonic").max("speed").idxmax("node").values)
    amp = resp.sel(node=node).values * 1e6
    freq = ds["frequency"].values
    rpm = np.broadcast_to(ds["speed_rpm"].values[:, None], amp.shape)
    top = float(np.nanmax(amp))
    ok = np.zeros(amp.shape, bool)
    for i in range(amp.shape[0]):
        ok[i] = shown_harmonics(amp[i], top)
    fig = go.Figure(
        go.Scatter(
            x=freq[ok],
            y=rpm[ok],
            mode="markers",
            marker=dict(
                color=np.log10(amp[ok]),
                colorscale="Viridis",
                size=7,
                colorbar=dict(title="log10 µm"),
            ),
            customdata=amp[ok],
            hovertemplate="%{x:.4g} Hz at %{y:.6g} rpm<br>%{customdata:.3g} µm",
            name=node,
        )
    )
    orders = json.loads(ds.attrs.get("marker_orders_json", "{}"))
    r = ds["speed_rpm"].values
    for label, order in orders.items():
        colour = "#d62728" if "mesh" in label else "#777777"
        fig.add_trace(
            go.Scatter(
                x=order * r / 60,
                y=r,
                mode="lines",
                name=label,
                line=dict(dash="dash", color=colour, width=1),
            )
        )
    fig.update_xaxes(title="frequency [Hz]", range=[0, float(freq[ok].max(initial=1.0)) * 1.05])
    fig.update_yaxes(title="input speed [rpm]")
    fig.update_layout(title=f"waterfall at {node}", **LAYOUT)
    fig.update_layout(legend=dict(orientation="h", y=-0.18))
    return fig


def stability_figure(sds: xr.Dataset) -> go.Figure:
    """The largest Floquet real part against speed, its decision tolerance, the unstable
    and undecided speeds, the unstable ranges shaded."""
    rpm = sds["speed"].values * RPM
    mr = sds["max_real"].values
    tol = sds["tol"].values
    fig = go.Figure()
    fig.add_trace(
        go.Scatter(
            x=np.concatenate([rpm, rpm[::-1]]),
            y=np.concatenate([tol, -tol[::-1]]),
            fill="toself",
            fillcolor="rgba(128,128,128,0.3)",
            line=dict(width=0),
            name="decision tolerance",
            hoverinfo="skip",
        )
    )
    fig.add_trace(
        go.Scatter(
            x=rpm,
            y=mr,
            mode="lines+markers",
            name="largest Floquet real part",
            customdata=tol,
            hovertemplate="%{x:.6g} rpm<br>%{y:.4g} ± %{customdata:.2g} 1/s",
        )
    )
    bad = ~sds["stable"].values.astype(bool)
    if bad.any():
        fig.add_trace(
            go.Scatter(
                x=rpm[bad],
                y=mr[bad],
                mode="markers",
                name="unstable",
                marker=dict(color="red", size=9),
            )
        )
    if "decided" in sds:
        und = ~sds["decided"].values.astype(bool)
        if und.any():
            fig.add_trace(
                go.Scatter(
                    x=rpm[und],
                    y=mr[und],
                    mode="markers",
                    name="undecided",
                    marker=dict(symbol="x", color="black", size=10),
                )
            )
    if "range_lower" in sds:
        for lo, hi in zip(sds["range_lower"].values, sds["range_upper"].values, strict=True):
            fig.add_vrect(x0=lo * RPM, x1=hi * RPM, fillcolor="red", opacity=0.15, line_width=0)
    fig.add_hline(y=0.0, line_color="black", line_width=1)
    fig.update_xaxes(title="input speed [rpm]")
    fig.update_yaxes(title="largest Floquet real part [1/s]")
    fig.update_layout(title="Floquet stability map", **LAYOUT)
    return fig


def campbell_figure(cds: xr.Dataset, fmax_hz: float | None = None) -> go.Figure:
    """Damped natural frequencies [Hz] and damping ratios against speed, each point coloured
    by its whirl ratio; order lines; critical speeds."""
    fig = make_subplots(
        rows=2, cols=1, shared_xaxes=True, row_heights=[0.65, 0.35], vertical_spacing=0.06
    )
    rpm = cds["speed_rpm"].values if "speed_rpm" in cds else cds["speed"].values * RPM
    freq = cds["frequency"].values
    zeta = cds["damping_ratio"].values
    whirl = np.nan_to_num(cds["whirl_ratio"].values)
    kind = cds["kind"].values.astype(str) if "kind" in cds else np.full(freq.shape, "")
    top = fmax_hz or _fmax(cds)
    for j in range(freq.shape[1]):
        f = freq[:, j]
        if not np.any(np.isfinite(f) & (f <= top)):
            continue
        common = dict(
            mode="lines+markers",
            line=dict(color="#bbbbbb", width=1),
            showlegend=False,
            marker=dict(
                color=whirl[:, j],
                colorscale=WHIRL_SCALE,
                cmin=-1,
                cmax=1,
                size=7,
                line=dict(width=0.5, color="#333"),
            ),
            customdata=np.stack([zeta[:, j], whirl[:, j]], -1),
            text=kind[:, j],
            name=f"branch {j}",
        )
        hover = (
            "%{x:.6g} rpm<br>%{y:.5g} Hz<br>%{text}<br>"
            "ζ %{customdata[0]:.3g}, whirl %{customdata[1]:.2f}"
        )
        fig.add_trace(go.Scatter(x=rpm, y=f, hovertemplate=hover, **common), row=1, col=1)
        fig.add_trace(
            go.Scatter(
                x=rpm,
                y=zeta[:, j],
                hovertemplate=hover.replace("%{y:.5g} Hz", "ζ %{y:.3g}"),
                **common,
            ),
            row=2,
            col=1,
        )
    speeds = cds["speed"].values
    for name, ratio in zip(cds["order"].values, cds["order_ratio"].values, strict=True):
        colour = "#d62728" if str(name).startswith("mesh") else "#555555"
        fig.add_trace(
            go.Scatter(
                x=rpm,
                y=ratio * speeds * HZ,
                mode="lines",
                name=str(name),
                line=dict(dash="dash", width=1, color=colour),
            ),
            row=1,
            col=1,
        )
    if "critical_speed" in cds and cds.sizes.get("critical", 0):
        crpm = cds["critical_speed"].values * RPM
        fig.add_trace(
            go.Scatter(
                x=crpm,
                y=cds["critical_frequency"].values,
                mode="markers",
                name="critical speed",
                marker=dict(symbol="circle-open", size=13, color="black", line=dict(width=2)),
                text=[
                    f"{o}, mode {m}, {k or w}"
                    for o, m, k, w in zip(
                        cds["critical_order"].values,
                        cds["critical_mode"].values,
                        cds["critical_kind"].values,
                        cds["critical_whirl"].values,
                        strict=True,
                    )
                ],
                hovertemplate="%{x:.6g} rpm, %{y:.5g} Hz<br>%{text}",
            ),
            row=1,
            col=1,
        )
    fig.update_yaxes(title="frequency [Hz]", range=[0, top], row=1, col=1)
    fig.update_yaxes(title="damping ratio [-]", row=2, col=1)
    fig.update_xaxes(title="input speed [rpm]", row=2, col=1)
    layout = {**LAYOUT, "height": 700}
    fig.update_layout(
        title="Campbell diagram (colour: whirl ratio, blue forward, red backward)", **layout
    )
    return fig


def _fmax(cds: xr.Dataset) -> float:
    """1.25 times the highest order line at the top speed, at least the second branch."""
    freq = cds["frequency"].values
    lines = cds["order_ratio"].values * float(cds["speed"].values.max()) * HZ
    lowest = np.sort(np.nanmax(np.where(np.isfinite(freq), freq, np.nan), axis=0))
    floor = float(lowest[min(1, lowest.size - 1)]) * 1.1 if lowest.size else 1.0
    high = float(np.nanmax(freq)) * 1.08 if np.isfinite(freq).any() else 1.0
    return min(high, max(1.25 * float(lines.max(initial=0.0)), floor))


def bode_figure(frf: Any) -> go.Figure:
    """Magnitude and phase of every driving-point (or first) receptance."""
    from ..results.frf import receptance_unit

    fig = make_subplots(rows=2, cols=1, shared_xaxes=True, row_heights=[0.65, 0.35])
    outs, ins = list(frf.outputs), list(frf.inputs)
    pairs = [(o, o) for o in outs if o in ins] or [(o, i) for o in outs for i in ins]
    f = np.asarray(frf.frequencies) * HZ
    for o, i in pairs[:6]:
        h = frf.receptance[:, outs.index(o), ins.index(i)]
        unit = receptance_unit(o, i, frf.unbalance)
        name = o if o == i else f"{o} / {i}"
        fig.add_trace(
            go.Scatter(
                x=f,
                y=np.abs(h),
                name=f"{name} [{unit}]",
                legendgroup=name,
                hovertemplate=f"%{{x:.5g}} Hz<br>%{{y:.3g}} {unit}",
            ),
            row=1,
            col=1,
        )
        fig.add_trace(
            go.Scatter(
                x=f,
                y=np.degrees(np.angle(h)),
                name=name,
                legendgroup=name,
                showlegend=False,
                hovertemplate="%{x:.5g} Hz<br>%{y:.1f} deg",
            ),
            row=2,
            col=1,
        )
    fig.update_yaxes(type="log", title="|H|", row=1, col=1)
    fig.update_yaxes(title="phase [deg]", range=[-185, 185], row=2, col=1)
    fig.update_xaxes(title="excitation frequency [Hz]", row=2, col=1)
    fig.update_layout(title="frequency response", **{**LAYOUT, "height": 620})
    return fig
