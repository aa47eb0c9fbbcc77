"""The report of a result directory: one self-contained HTML file that opens offline, for a
customer or a certification body (API 684 / 617 style).

1. Read what a directory holds (``results.nc``/``summary.json`` of ``rheolin run``,
   ``sweep.*`` and ``stability_map.nc`` of ``sweep``, ``campbell.nc``, ``modes.nc``,
   ``frf.nc``) and the model file the results record (checked by its SHA-256):
   :func:`read_directory`.
2. Build the page: verdicts with their uncertainty, the preloaded operating point, the model
   drawing, interactive figures (plotly: zoom, hover, hide curves), critical speeds,
   resonances with amplification factors and separation margins, unstable ranges with
   bounds and mechanisms, the inputs and files for traceability: :func:`build_report`.
3. Write it atomically as ``report.html``: :func:`write_report` (``rheolin report DIR``,
   or ``--report`` on ``run``, ``sweep`` and ``campbell``).

>>> import tempfile, pathlib
>>> out = write_report(tempfile.mkdtemp())
>>> out.name, "no rheolin result file" in out.read_text(encoding="utf-8")
('report.html', True)
"""

from .build import REPORT_FILE, build_report, write_report
from .collect import ResultDirectory, read_directory

__all__ = ["REPORT_FILE", "ResultDirectory", "build_report", "read_directory", "write_report"]
