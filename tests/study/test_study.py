"""Studies through the Python API: serial and Dask give the same results; a parameter study
matches single solves of independently built models and closed-form band edges; resume,
refusal of another study's checkpoint, failed points, stale files."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from threadpoolctl import threadpool_limits

from rheolin.cli.parse import parse_speeds
from rheolin.results import solve_point
from rheolin.results.sweep import sweep_speeds
from rheolin.study import (
    MAP_PRECISION,
    Settings,
    StudyBusy,
    StudyConflict,
    StudyInterrupted,
    StudySpec,
    run_study,
)
from rheolin.study.chunks import floquet_results, read_chunk
from rheolin.study.executor import local_cluster

sys.path.insert(0, str(Path(__file__).parent))
from study_cases import BAND, band_model, rpm

SPEEDS = parse_speeds("900:1100:25rpm")  # across the band 955..1050 rpm, as the CLI reads it


@pytest.fixture(autouse=True)
def _allow_underflow():
    with np.errstate(under="ignore"):
        yield


@pytest.fixture(scope="module")
def client():
    """One local cluster (2 processes) for the module."""
    with local_cluster(2) as c:
        yield c


@pytest.fixture(scope="module")
def serial(band_file):
    return run_study(StudySpec.create(band_file, SPEEDS))


def _same(a: xr.Dataset, b: xr.Dataset, rtol: float = 1e-12) -> None:
    """Equal values (floats to ``rtol``), names and coordinates; timings left out."""
    a, b = a.drop_vars("seconds", errors="ignore"), b.drop_vars("seconds", errors="ignore")
    assert sorted(a.data_vars) == sorted(b.data_vars)
    for name in a.variables:
        x, y = a[name].values, b[name].values
        if x.dtype.kind == "f":
            np.testing.assert_allclose(x, y, rtol=rtol, atol=0, err_msg=name)
        else:
            np.testing.assert_array_equal(x, y, err_msg=name)


def test_workers_run_with_one_blas_thread_and_glibc_malloc_defaults(client):
    """The local cluster's workers: one BLAS thread, and none of Dask's fixed malloc trim
    threshold (it turns off glibc's adaptive mmap threshold: the lattice search ran 1.6x
    slower in a worker than in a plain process)."""

    def env() -> tuple[str | None, str | None, list[int]]:
        import os

        from threadpoolctl import threadpool_info

        return (
            os.environ.get("OPENBLAS_NUM_THREADS"),
            os.environ.get("MALLOC_TRIM_THRESHOLD_"),
            [int(i["num_threads"]) for i in threadpool_info() if i["user_api"] == "blas"],
        )

    for blas, trim, threads in client.run(env).values():
        assert blas == "1"
        assert trim is None
        assert all(t == 1 for t in threads)


def test_parallel_equals_serial(serial, band_file, client):
    spec = StudySpec.create(band_file, SPEEDS)
    parallel = run_study(spec, client=client, chunk_size=2)
    _same(parallel.dataset, serial.dataset)
    (a,), (b,) = serial.maps[0].ranges, parallel.maps[0].ranges
    assert (a.lower, a.upper, a.mechanism, a.label) == (b.lower, b.upper, b.mechanism, b.label)
    _same(parallel.stability_dataset(), serial.stability_dataset())


def test_serial_study_equals_the_sweep_and_the_closed_form(serial, band_file):
    """Against ``sweep_speeds`` (one solve after another, no study machinery; it warm-starts
    each speed from the previous one, so the two agree to the solver's tolerance, not to the
    bit) and the band edges sqrt(k_x / m) = 100, sqrt(k_y / m) = 110 rad/s."""
    with threadpool_limits(1):  # as on the study's workers: the same floating-point sums
        ref = sweep_speeds(band_model(), SPEEDS, order=2)
    ds = serial.dataset
    assert ds["response"].dims == ("speed", "harmonic", "node")
    for name in ref.data_vars:
        if name in ("residual", "iterations", "seconds", "solve_seconds"):
            continue  # how the solver got there, not the answer
        x, y = ds[name].values, ref[name].values
        if x.dtype.kind == "f":
            scale = np.nanmax(np.abs(y), initial=0.0)
            np.testing.assert_allclose(x, y, rtol=1e-9, atol=1e-9 * scale, err_msg=name)
        else:
            np.testing.assert_array_equal(x, y, err_msg=name)
    inside = (SPEEDS > 100.0) & (SPEEDS < 110.0)  # (k_x - m W^2)(k_y - m W^2) < 0
    assert inside.sum() == 4
    np.testing.assert_array_equal(ds["stable"].values, ~inside)
    np.testing.assert_array_equal(ds["status"].values, np.where(inside, 4, 0))
    (band,) = serial.maps[0].ranges
    assert band.lower == pytest.approx(100.0, rel=MAP_PRECISION)
    assert band.upper == pytest.approx(110.0, rel=MAP_PRECISION)
    assert band.mechanism == "asymmetric shaft band"


def test_parameter_study_matches_single_solves_and_the_band_edges(band_file, client):
    """k_y of the spring and its damping in x varied on a 4 x 2 grid: each grid point equals
    a solve of the model built with the Python API; the band's upper edge is sqrt(k_y / m)."""
    ky = [1.1e4, 1.2e4, 1.3e4, 1.4e4]
    vary = {
        "bearings.spring.stiffness[1]": "1.1e4:1.4e4:4 N/m",
        "bearings.spring.damping[0]": "0, 0.5 N*s/m",
    }
    speeds = rpm(np.arange(900.0, 1201.0, 25.0))  # the band's upper edge reaches 1130 rpm
    res = run_study(StudySpec.create(band_file, speeds, vary), client=client)
    ds = res.dataset
    assert ds["response"].dims == (*vary, "speed", "harmonic", "node")
    assert ds["bearings.spring.stiffness[1]"].attrs["units"] == "N/m"
    np.testing.assert_array_equal(ds["bearings.spring.stiffness[1]"].values, ky)
    for i, j, k in [(0, 0, 0), (3, 1, 4), (1, 1, 12)]:
        ref = solve_point(band_model(ky[i], [0.0, 0.5][j]), float(speeds[k]), order=2).solution
        got = ds.isel({"bearings.spring.stiffness[1]": i, "bearings.spring.damping[0]": j})
        got = got.isel(speed=k)
        amp = 2 * np.hypot(*np.abs(ref.harmonic(1)[:2]))
        assert float(got["response"].sel(harmonic=1, node="r:0")) == pytest.approx(amp, rel=1e-12)
        assert int(got["status"]) == ref.status and int(got["stable"]) == int(ref.stable)
        assert float(got["max_floquet_real"]) == pytest.approx(ref.max_floquet_real, rel=1e-12)
    for k in ky:
        band = res.map(**{"bearings.spring.stiffness[1]": k, "bearings.spring.damping[0]": 0.0})
        (r,) = band.ranges
        assert r.lower == pytest.approx(100.0, rel=MAP_PRECISION)
        assert r.upper == pytest.approx(np.sqrt(k), rel=MAP_PRECISION)
    sds = res.stability_dataset()
    assert sds["max_real"].dims == (*vary, "speed") and sds.sizes["range"] >= 4


def test_an_interrupted_study_resumes_with_the_missing_points_only(band_file, serial, tmp_path):
    spec = StudySpec.create(band_file, SPEEDS)
    seen = []

    def stop_after_three(event):
        seen.append(event.done)
        if event.done >= 3:
            raise KeyboardInterrupt

    with pytest.raises(StudyInterrupted) as stop:
        run_study(spec, out=tmp_path, chunk_size=1, progress=stop_after_three)
    assert (stop.value.done, stop.value.total) == (3, SPEEDS.size)
    chunks = sorted((tmp_path / "checkpoint").glob("chunk-*.nc"))
    assert len(chunks) == 3 and not (tmp_path / "sweep.nc").exists()
    events = []
    res = run_study(spec, out=tmp_path, progress=events.append)
    assert (res.resumed, res.computed) == (3, SPEEDS.size - 3)
    assert events[0].resumed == 3 and events[-1].done == events[-1].total
    _same(res.dataset, serial.dataset)
    _same(xr.open_dataset(tmp_path / "sweep.nc").drop_vars("map_max_real"), serial.dataset)
    points = [
        p
        for c in (tmp_path / "checkpoint").glob("chunk-*.nc")
        for p in read_chunk(c)["point"].values
    ]
    assert sorted(points) == list(range(SPEEDS.size))  # none lost, none twice
    again = run_study(spec, out=tmp_path)
    assert (again.resumed, again.computed) == (SPEEDS.size, 0)
    # the map was cached: its Floquet results and refined bounds come back unchanged
    assert again.maps[0].ranges == serial.maps[0].ranges


def test_a_changed_model_file_is_never_mixed_with_old_points(tmp_path):
    model = tmp_path / "band.toml"
    model.write_text(BAND)
    run_study(StudySpec.create(model, SPEEDS[:4]), out=tmp_path / "out")
    model.write_text(BAND.replace('"1.21e4 N/m"', '"1.44e4 N/m"'))
    changed = StudySpec.create(model, SPEEDS[:4])
    with pytest.raises(StudyConflict, match="the model file changed"):
        run_study(changed, out=tmp_path / "out")
    res = run_study(changed, out=tmp_path / "out", overwrite=True)
    assert (res.resumed, res.computed) == (0, 4)
    fresh = run_study(changed)
    _same(res.dataset, fresh.dataset)
    (tmp_path / "old.toml").write_text(BAND)
    old = run_study(StudySpec.create(tmp_path / "old.toml", SPEEDS[:4]))
    differ = old.dataset["response"].values != fresh.dataset["response"].values
    assert differ.any()  # (the unbalance at 30 deg sees k_y): the old points would show


def test_a_failing_point_is_reported_and_the_study_goes_on(
    band_file, serial, tmp_path, monkeypatch
):
    from rheolin.study import worker

    real = worker._solve
    bad = float(SPEEDS[4])

    def flaky(lm, speed, *args):
        if speed == bad:
            raise RuntimeError("solver exploded")
        return real(lm, speed, *args)

    monkeypatch.setattr(worker, "_solve", flaky)
    spec = StudySpec.create(band_file, SPEEDS, settings=Settings(stability_map=False))
    events = []
    res = run_study(spec, out=tmp_path, progress=events.append)
    assert res.failures == {4: "RuntimeError: solver exploded"}
    assert [f for e in events for f in e.failures] == [(4, "RuntimeError: solver exploded")]
    ds = res.dataset
    assert ds["status"].values[4] == -1 and ds["success"].values[4] == 0
    assert ds["message"].values[4] == "RuntimeError: solver exploded"
    assert np.isnan(ds["response"].values[4]).all()
    keep = np.arange(SPEEDS.size) != 4
    np.testing.assert_array_equal(
        ds["response"].values[keep], serial.dataset["response"].values[keep]
    )
    monkeypatch.setattr(worker, "_solve", real)
    again = run_study(spec, out=tmp_path)  # the failed point is missing: computed now
    assert (again.resumed, again.computed, again.failures) == (SPEEDS.size - 1, 1, {})
    np.testing.assert_array_equal(again.dataset["response"], serial.dataset["response"])


def test_stale_temporary_files_go_and_a_busy_directory_is_refused(band_file, tmp_path):
    import fcntl

    spec = StudySpec.create(band_file, SPEEDS[:2], settings=Settings(stability_map=False))
    run_study(spec, out=tmp_path)
    stale = [
        tmp_path / ".sweep.nc.abc123xy.tmp",
        tmp_path / "checkpoint" / ".chunk-0000001.nc.q1w2e3r4.tmp",
    ]
    for p in stale:
        p.write_bytes(b"half a file")
    mine = tmp_path / ".notes.txt.abc123xy.tmp"  # not ours: left alone
    mine.write_text("keep")
    run_study(spec, out=tmp_path)
    assert not any(p.exists() for p in stale) and mine.exists()
    with open(tmp_path / ".rheolin.lock", "a+") as fh:
        fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        with pytest.raises(StudyBusy):
            run_study(spec, out=tmp_path)


def test_chunk_files_are_self_contained(serial, band_file, tmp_path):
    """Every chunk opens on its own with xarray and holds its points' Floquet results."""
    spec = StudySpec.create(band_file, SPEEDS[:3])
    run_study(spec, out=tmp_path, chunk_size=2)
    chunks = sorted((tmp_path / "checkpoint").glob("chunk-*.nc"))
    assert [c.name for c in chunks] == ["chunk-0000000.nc", "chunk-0000002.nc"]
    ds = read_chunk(chunks[0])
    assert ds.attrs["study_key"] == spec.key and ds["point"].values.tolist() == [0, 1]
    results = floquet_results(ds)
    assert sorted(results) == [0, 1]
    assert results[1].max_real == float(serial.dataset["max_floquet_real"][1])


def test_the_cli_runs_on_an_existing_cluster(serial, band_file, client, tmp_path):
    """``rheolin sweep --scheduler ADDRESS``: the same results as the serial study; the
    cluster stays up for its owner."""
    from run_cli import cli

    address = client.scheduler.address
    res = cli(
        "sweep",
        str(band_file),
        "--speeds",
        "900:1100:25rpm",
        "--out",
        str(tmp_path),
        "--scheduler",
        address,
    )
    assert res.returncode == 1, res.stderr  # unstable points
    _same(xr.open_dataset(tmp_path / "sweep.nc").drop_vars("map_max_real"), serial.dataset)
    assert client.submit(sum, [1, 2]).result() == 3
