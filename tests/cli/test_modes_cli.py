"""``rheolin modes`` in a subprocess: the torsional and axial modes it lists are those of the
torsion-only and axial-only eigenproblems of the assembled matrices (uncoupled from bending
on an axisymmetric rotor: a separate, smaller eigenproblem), the lateral ones come in
backward/forward pairs, and modes.nc reopens with its shapes."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import scipy.linalg as sla
import xarray as xr

from rheolin.io import parse_model
from rheolin.results.units import missing_units

ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "COLUMNS": "160"}

ROTOR = """
[model]
input_body = "rotor"

[[shafts]]
name = "rotor"
positions = "0 100 200 300 400 mm"
outer_diameter = "40 mm"
material = "steel"
disks = [{ node = 2, outer_diameter = "250 mm", width = "30 mm" }]

[[shafts.bearings]]
name = "left"
node = 0
components = ["ux", "uy", "uz", "phiz"]
stiffness = ["2e7 N/m", "2e7 N/m", "1e8 N/m", "1e4 N*m/rad"]

[[shafts.bearings]]
name = "right"
node = 4
stiffness = "2e7 N/m"
"""


def test_modes_lists_labelled_modes_that_match_the_uncoupled_eigenproblems(tmp_path: Path) -> None:
    (tmp_path / "rotor.toml").write_text(ROTOR)
    res = subprocess.run(
        [sys.executable, "-m", "rheolin.cli", "modes", str(tmp_path / "rotor.toml"), "--speed",
         "3000rpm", "--count", "16", "--out", str(tmp_path / "out")],
        capture_output=True, text=True, env=ENV, timeout=300,
    )  # fmt: skip
    assert res.returncode == 0, res.stderr
    rows = re.findall(
        r"│\s*(\d+)\s*│\s*([0-9.]+)\s*│\s*([-0-9.e]+)\s*│\s*([a-z ()+]+?)\s*│", res.stdout
    )
    assert len(rows) == 16
    kinds = [k for _, _, _, k in rows]
    freq = np.array([float(f) for _, f, _, _ in rows])
    a = parse_model(ROTOR).model.assemble(3000 * np.pi / 30)
    K, M = a.system.K[0].toarray(), a.system.M[0].toarray()
    for comp, kind in (("phiz", "torsional"), ("uz", "axial")):
        dofs = [i for i, lab in enumerate(a.dof_labels) if lab[2] == comp]
        lam = sla.eigh(K[np.ix_(dofs, dofs)], M[np.ix_(dofs, dofs)], eigvals_only=True)
        ref = np.sqrt(lam) / (2 * np.pi)
        got = freq[[k == kind for k in kinds]]
        assert got.size >= 1
        assert np.allclose(got, ref[: got.size], rtol=1e-5), (kind, got, ref)  # 3 decimals
    lateral = [k for k in kinds if k.startswith("lateral")]
    assert lateral[:4] == ["lateral backward", "lateral forward"] * 2
    ds = xr.open_dataset(tmp_path / "out" / "modes.nc")
    assert missing_units(ds) == []
    assert ds["shape"].shape == (16, len(a.dof_labels), 2)
    np.testing.assert_allclose(ds["energy_share"].sum("motion").values, 1.0, rtol=1e-12)
    assert (tmp_path / "out" / "modes.png").stat().st_size > 20_000
