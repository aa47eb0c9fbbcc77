"""Studies: many operating points (speeds times parameter values), in parallel on Dask,
checkpointed and resumable, with a stability map per parameter combination.

>>> from rheolin.data import example_path
>>> from rheolin.study import Settings, StudySpec, run_study
>>> spec = StudySpec.create(example_path("rotor"), [300.0, 400.0],
...                         {"bearings.free_end.damping": "500,800 N*s/m"},
...                         Settings(stability=False, stability_map=False))
>>> run_study(spec).dataset["success"].dims
('bearings.free_end.damping', 'speed')

Modules: :mod:`~rheolin.study.params` (paths and values), :mod:`~rheolin.study.spec` (the
study and its key), :mod:`~rheolin.study.worker` (what a worker runs),
:mod:`~rheolin.study.chunks` (chunk files), :mod:`~rheolin.study.store` (checkpoint),
:mod:`~rheolin.study.executor` (serial or Dask), :mod:`~rheolin.study.assemble` (the
Dataset), :mod:`~rheolin.study.files` (result files), :mod:`~rheolin.study.run`.
"""

from .assemble import STATUS_ERROR
from .params import Parameter, ParameterError, parse_vary
from .run import MAP_PRECISION, StudyInterrupted, StudyProgress, StudyResult, run_study
from .spec import Settings, StudySpec
from .store import StudyBusy, StudyConflict

__all__ = [
    "MAP_PRECISION",
    "STATUS_ERROR",
    "Parameter",
    "ParameterError",
    "Settings",
    "StudyBusy",
    "StudyConflict",
    "StudyInterrupted",
    "StudyProgress",
    "StudyResult",
    "StudySpec",
    "parse_vary",
    "run_study",
]
