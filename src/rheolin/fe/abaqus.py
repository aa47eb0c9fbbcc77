"""Abaqus global matrices: ``*MATRIX GENERATE`` / ``*MATRIX OUTPUT, FORMAT=MATRIX INPUT``
(``jobname_STIF1.mtx``, ``jobname_MASS1.mtx``, optionally ``_DMPV1``) and the nodes of the
``.inp``, as an :class:`~rheolin.fe.matrices.FEModel`.

The matrix input format has one nonzero per line: ``row node, row DOF, column node, column
DOF, value`` (DOFs 1-3 translations, 4-6 rotations), a symmetric matrix given as its lower or
upper triangle or whole; lines starting with ``*`` or ``**`` are keywords and comments. No
maintained Python reader exists for it (``meshio`` reads the mesh, renumbering the nodes), so
this one is small and strict: a line that is not five fields, a DOF outside 1-6 or a
non-finite value is refused with its line number.

Abaqus has no units: ``units="SI"`` (N, m, kg) or ``"mm-t-s"`` (N, mm, tonne), converted to SI
entry by entry (a stiffness entry ``K_ab`` in N/mm times ``1e3 x 1e-3^r``, ``r`` the number
of rotational indices; masses alike).

>>> import tempfile, pathlib
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> k = "** two springs\\n1,1, 1,1, 2.0\\n2,1, 1,1, -1.0\\n2,1, 2,1, 1.0\\n"
>>> _ = (d / "k.mtx").write_text(k)
>>> _ = (d / "m.mtx").write_text("1,1, 1,1, 1.0\\n2,1, 2,1, 1.0\\n")
>>> _ = (d / "n.inp").write_text("*NODE\\n1, 0., 0., 0.\\n2, 1., 0., 0.\\n*ELEMENT\\n")
>>> fe = read_abaqus(d / "k.mtx", d / "m.mtx", nodes=d / "n.inp")
>>> fe.K.toarray().tolist(), fe.node_ids.tolist()
([[2.0, -1.0], [-1.0, 1.0]], [1, 2])
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ..errors import ModelError
from .matrices import FEModel

__all__ = ["read_abaqus", "read_abaqus_nodes", "read_matrix_input"]

#: Unit systems: (force-per-length factor of a translational stiffness or a mass, length).
UNITS = {"SI": (1.0, 1.0), "mm-t-s": (1e3, 1e-3)}


def read_matrix_input(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(row_keys, col_keys, values)`` of an Abaqus matrix-input file; a key is ``(node, dof)``
    as one row of an ``(n, 2)`` integer array (DOF 1-6)."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ModelError(f"{path}: cannot read the matrix file ({exc.strerror})") from None
    rows: list[tuple[int, int, int, int]] = []
    vals: list[float] = []
    for number, line in enumerate(text.splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("*"):
            continue
        fields = [f.strip() for f in line.split(",")]
        if fields and fields[-1] == "":
            fields.pop()
        if len(fields) != 5:
            raise ModelError(
                f"{path}:{number}: expected 'row node, row dof, column node, column dof, value', "
                f"got {len(fields)} fields"
            )
        try:
            a, b, c, d = (int(f) for f in fields[:4])
            v = float(fields[4].replace("D", "E").replace("d", "e"))
        except ValueError:
            raise ModelError(f"{path}:{number}: not numbers: {line!r}") from None
        if not (1 <= b <= 6 and 1 <= d <= 6):
            raise ModelError(
                f"{path}:{number}: DOF {b if not 1 <= b <= 6 else d} is not a structural DOF "
                "(1-6: translations, rotations); export the structural matrices only"
            )
        if not np.isfinite(v):
            raise ModelError(f"{path}:{number}: non-finite entry {fields[4]!r}")
        rows.append((a, b, c, d))
        vals.append(v)
    if not rows:
        raise ModelError(f"{path}: no matrix entries")
    arr = np.asarray(rows, dtype=np.int64)
    return arr[:, :2], arr[:, 2:], np.asarray(vals)


def read_abaqus_nodes(path: str | Path) -> dict[int, np.ndarray]:
    """Node coordinates from the ``*NODE`` blocks of an Abaqus ``.inp`` (``id, x, y, z``)."""
    path = Path(path)
    try:
        lines = path.read_text().splitlines()
    except OSError as exc:
        raise ModelError(f"{path}: cannot read the input file ({exc.strerror})") from None
    out: dict[int, np.ndarray] = {}
    inside = False
    for number, raw in enumerate(lines, 1):
        line = raw.strip()
        if line.startswith("**") or not line:
            continue
        if line.startswith("*"):
            keyword = line[1:].split(",")[0].strip().upper()
            inside = keyword == "NODE"
            continue
        if inside:
            fields = [f.strip() for f in line.split(",") if f.strip()]
            try:
                node = int(fields[0])
                xyz = [float(f) for f in fields[1:4]] + [0.0] * (4 - len(fields))
            except (ValueError, IndexError):
                raise ModelError(
                    f"{path}:{number}: not a node line 'id, x, y, z': {raw!r}"
                ) from None
            out[node] = np.asarray(xyz[:3])
    if not out:
        raise ModelError(f"{path}: no *NODE block")
    return out


def _assemble(
    keys: dict[tuple[int, int], int],
    parts: tuple[np.ndarray, np.ndarray, np.ndarray],
    factor: float,
    length: float,
    name: str,
) -> sp.csr_array:
    r, c, v = parts
    i = np.array([keys[(int(a), int(b))] for a, b in r])
    j = np.array([keys[(int(a), int(b))] for a, b in c])
    # SI: N/mm -> N/m (1e3), each rotational index turns one mm into m (1e-3)
    rot = (r[:, 1] > 3).astype(int) + (c[:, 1] > 3).astype(int)
    v = v * factor * length**rot if factor != 1.0 else v
    n = len(keys)
    A = sp.coo_array((v, (i, j)), shape=(n, n)).tocsr()
    A.sum_duplicates()
    upper, lower = sp.triu(A, 1), sp.tril(A, -1)
    if upper.nnz == 0 or lower.nnz == 0:  # one triangle: mirror it
        A = sp.csr_array(A + (upper + lower).T)
    return A


def read_abaqus(
    stiffness: str | Path,
    mass: str | Path,
    *,
    nodes: str | Path | dict[int, np.ndarray] | None = None,
    damping: str | Path | None = None,
    units: str = "SI",
) -> FEModel:
    """An :class:`FEModel` from Abaqus matrix-input files and the ``.inp`` with the nodes.

    The DOFs are the union of those in the files, ordered by node number then DOF. Without
    ``nodes`` the coordinates are unknown (zeros): give them for couplings by position.
    """
    if units not in UNITS:
        raise ModelError(f"`units` must be one of {', '.join(UNITS)}, got {units!r}")
    factor, length = UNITS[units]
    parts = {"K": read_matrix_input(stiffness), "M": read_matrix_input(mass)}
    if damping is not None:
        parts["D"] = read_matrix_input(damping)
    allkeys = np.unique(np.vstack([k for p in parts.values() for k in p[:2]]), axis=0)
    keys = {(int(a), int(b)): i for i, (a, b) in enumerate(allkeys)}
    ids = np.unique(allkeys[:, 0])
    if nodes is None:
        xyz = np.zeros((ids.size, 3))
    else:
        table = read_abaqus_nodes(nodes) if not isinstance(nodes, dict) else nodes
        missing = [int(i) for i in ids if int(i) not in table]
        if missing:
            raise ModelError(
                f"nodes: FE node(s) {missing[:5]} of the matrices are not in the *NODE blocks"
            )
        xyz = np.array([table[int(i)] for i in ids], dtype=float) * length
    index = {int(i): k for k, i in enumerate(ids)}
    mats = {name: _assemble(keys, p, factor, length, f"{name}") for name, p in parts.items()}
    return FEModel(
        mats["K"],
        mats["M"],
        xyz,
        np.array([index[int(a)] for a in allkeys[:, 0]]),
        allkeys[:, 1] - 1,
        node_ids=ids,
        D=mats.get("D"),
    )
