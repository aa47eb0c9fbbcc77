"""Abaqus matrix-input files (``*MATRIX OUTPUT, FORMAT=MATRIX INPUT``) and ``*NODE`` blocks:
a scikit-fem solid written as Abaqus would (mm-t-s units, one triangle, shuffled lines,
keywords and comments) reads back as its own matrices in SI; the unit conversion of rotational
entries against its closed form; malformed files refused with the line."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from rheolin.errors import ModelError
from rheolin.fe.abaqus import read_abaqus

pytest.importorskip("skfem")
from rheolin.fe.solid import solid_model, tensor_block

IDS0 = 1001  # Abaqus node numbers need not start at 1


def _write_matrix(path, A, fe, scale, triangle, rng):  # type: ignore[no-untyped-def]
    C = sp.coo_array(A)
    keep = C.row >= C.col if triangle == "lower" else C.row == C.row
    lines = [
        f"{IDS0 + fe.dof_node[i]}, {fe.dof_component[i] + 1}, "
        f"{IDS0 + fe.dof_node[j]}, {fe.dof_component[j] + 1}, {v * scale:.17e}"
        for i, j, v in zip(C.row[keep], C.col[keep], C.data[keep], strict=True)
    ]
    rng.shuffle(lines)
    path.write_text("** written by the test as Abaqus does\n*MATRIX\n" + "\n".join(lines) + "\n")


@pytest.fixture
def block(tmp_path):  # type: ignore[no-untyped-def]
    fe = solid_model(*tensor_block((0.2, 0.05, 0.04), (8, 2, 2)))
    rng = np.random.default_rng(1)
    # mm-t-s: stiffness N/mm = 1e-3 N/m, mass tonne = 1e3 kg, coordinates mm
    _write_matrix(tmp_path / "job_STIF1.mtx", fe.K, fe, 1e-3, "lower", rng)
    _write_matrix(tmp_path / "job_MASS1.mtx", fe.M, fe, 1e-3, "square", rng)
    nodes = "\n".join(
        f"{IDS0 + i}, {x * 1e3:.17g}, {y * 1e3:.17g}, {z * 1e3:.17g}"
        for i, (x, y, z) in enumerate(fe.coordinates)
    )
    (tmp_path / "job.inp").write_text(
        f"*HEADING\nblock\n*NODE, NSET=ALL\n{nodes}\n*ELEMENT, TYPE=C3D8\n1, 1001, 1002\n"
    )
    return fe, tmp_path


def test_solid_reads_back_as_its_own_matrices_in_si(block):  # type: ignore[no-untyped-def]
    fe, d = block
    got = read_abaqus(d / "job_STIF1.mtx", d / "job_MASS1.mtx", nodes=d / "job.inp",
                      units="mm-t-s")  # fmt: skip
    assert got.n_dof == fe.n_dof
    assert np.array_equal(got.node_ids, IDS0 + np.arange(fe.coordinates.shape[0]))
    assert np.allclose(got.coordinates, fe.coordinates, rtol=0, atol=1e-15)
    for a, b in ((got.K, fe.K), (got.M, fe.M)):
        assert abs(a - b).max() <= 1e-14 * abs(b).max()
    # and its modes are the solid's: the lowest elastic frequencies (dense generalized eigh;
    # shift-invert at -1 next to eigenvalues of 1e9 was too ill-conditioned to compare)
    a = sla.eigh(got.K.toarray(), got.M.toarray(), eigvals_only=True)[6:12]
    b = sla.eigh(fe.K.toarray(), fe.M.toarray(), eigvals_only=True)[6:12]
    assert np.allclose(a, b, rtol=1e-10)


def test_rotational_entries_convert_by_their_units(tmp_path):  # type: ignore[no-untyped-def]
    """A node with a rotational spring 5 N mm/rad, a coupling 2 N/rad and a translational
    spring 3 N/mm; inertia 4 t mm^2 and mass 0.5 t: in SI 5e-3 N m/rad, 2 N/rad, 3e3 N/m,
    4e-3 kg m^2, 500 kg."""
    (tmp_path / "k.mtx").write_text("7,1, 7,1, 3.\n7,6, 7,1, 2.\n7,6, 7,6, 5.\n")
    (tmp_path / "m.mtx").write_text("7,1, 7,1, 0.5\n7,6, 7,6, 4.\n")
    fe = read_abaqus(tmp_path / "k.mtx", tmp_path / "m.mtx", nodes={7: np.zeros(3)},
                     units="mm-t-s")  # fmt: skip
    assert fe.dof_component.tolist() == [0, 5]
    assert np.allclose(fe.K.toarray(), [[3e3, 2.0], [2.0, 5e-3]], rtol=1e-15)
    assert np.allclose(fe.M.toarray(), [[500.0, 0.0], [0.0, 4e-3]], rtol=1e-15)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("1,1, 1,1\n", r"k\.mtx:1: expected"),
        ("1,1, 1,1, 2.0\n1,8, 1,8, 1.0\n", r"k\.mtx:2: DOF 8"),
        ("1,1, 1,1, nan\n", r"k\.mtx:1: non-finite"),
        ("1,a, 1,1, 2.0\n", r"k\.mtx:1: not numbers"),
        ("** only a comment\n", r"no matrix entries"),
    ],
)
def test_malformed_matrix_files_are_refused_with_the_line(tmp_path, text, match):  # type: ignore[no-untyped-def]
    (tmp_path / "k.mtx").write_text(text)
    (tmp_path / "m.mtx").write_text("1,1, 1,1, 1.0\n")
    with pytest.raises(ModelError, match=match):
        read_abaqus(tmp_path / "k.mtx", tmp_path / "m.mtx")


def test_nodes_missing_from_the_input_file_are_named(tmp_path):  # type: ignore[no-untyped-def]
    (tmp_path / "k.mtx").write_text("1,1, 1,1, 2.0\n2,1, 2,1, 2.0\n")
    (tmp_path / "m.mtx").write_text("1,1, 1,1, 1.0\n2,1, 2,1, 1.0\n")
    (tmp_path / "n.inp").write_text("*NODE\n1, 0, 0, 0\n")
    with pytest.raises(ModelError, match=r"FE node\(s\) \[2\]"):
        read_abaqus(tmp_path / "k.mtx", tmp_path / "m.mtx", nodes=tmp_path / "n.inp")
    with pytest.raises(ModelError, match="units"):
        read_abaqus(tmp_path / "k.mtx", tmp_path / "m.mtx", units="inch")
