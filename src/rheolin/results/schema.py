"""The versioned schema of ``summary.json`` (``rheolin run``) and ``sweep.json`` (``sweep``).

Both files carry ``"schema": "rheolin.summary"`` / ``"rheolin.sweep"`` and
``"schema_version"`` (:data:`SCHEMA_VERSION`); flags are JSON booleans (``true``/``false``),
a quantity that was not computed is ``null``. See ``docs/results-schema.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

__all__ = ["SCHEMA_VERSION", "Verdict", "point_verdict"]

#: Version of the JSON result files; raised on every incompatible change.
SCHEMA_VERSION = 1


@dataclass
class Verdict:
    """Whether a run succeeded, and what a reader must be told about it."""

    ok: bool
    notes: list[str] = field(default_factory=list)


def point_verdict(summary: dict[str, Any]) -> Verdict:
    """The verdict of one operating point from its summary: ``ok`` when the solution
    converged and its stability is not unstable or undecided; ``notes`` say what is uncertain
    (an undecided stability verdict and why, a truncated harmonic set).

    >>> v = point_verdict({"success": True, "stability": "undecided", "stability_decided": False})
    >>> v.ok, v.notes[0][:22]
    (False, 'stability is UNDECIDED')
    """
    notes = []
    if summary.get("stability_decided") is False:
        why = summary.get("stability_open") or "the Floquet truncation could still flip the verdict"
        notes.append(f"stability is UNDECIDED: {why} (docs/stability.md)")
    elif summary.get("stability") == "undecided":
        notes.append(
            "stability is UNDECIDED: the largest Floquet real part is zero within its "
            "tolerance (an undamped motion; add its damping to decide; docs/stability.md)"
        )
    notes += [str(w) for w in summary.get("warnings", [])]
    # an undecided stability verdict is not a pass (docs/cli.md, exit codes)
    ok = bool(summary.get("success")) and summary.get("stability") != "undecided"
    return Verdict(ok, notes)
