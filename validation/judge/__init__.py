"""The judge wing's file layer: another engine's run of a scene as a trajectory file.

* :mod:`.columns`: the column schema, declared once (name, unit, frame, group, per mass);
* :mod:`.read`: ``read_trajectory`` (CSV or Parquet -> ``ExternalTrajectory``, every bad file one
  line naming the row and column);
* :mod:`.write`: ``write_trajectory`` (a plant's ``Trajectory`` -> a file, full precision, atomic);
* :mod:`.record`: the ``ExternalTrajectory`` record and the quaternion sign convention;
* :mod:`.judge`: ``judge`` (``tumble judge``): the file as one more plant beside the built-in
  plants, or against a reference pack; :mod:`.reference_pack`, :mod:`.pack_readme`:
  ``tumble reference``;
* :mod:`.table`, :mod:`.csv_text`, :mod:`.parquet_table`, :mod:`.errors`: the checks, the two
  encodings and the error.

The format is documented for people writing such files in ``docs/trajectory-format.md``.

The package is callable: ``validation.judge(scene, trajectory_file, ...)`` is
:func:`validation.judge.judge.judge` whether the name ``validation.judge`` holds the function
(``validation``'s lazy export) or this package (once a submodule was imported, Python's import
sets the package there).
"""

import sys
import types

from validation._lazy import lazy_exports

_PUBLIC = {
    "COLUMNS": "validation.judge.columns",
    "ColumnGroup": "validation.judge.columns",
    "TrajectoryFormat": "validation.judge.columns",
    "TrajectoryFileError": "validation.judge.errors",
    "ExternalTrajectory": "validation.judge.record",
    "read_trajectory": "validation.judge.read",
    "write_trajectory": "validation.judge.write",
    "judge_request": "validation.judge.judge",
    "run_judge": "validation.judge.judge",
    "write_pack": "validation.judge.reference_pack",
    "read_pack": "validation.judge.reference_pack",
    "GRID_TOL": "validation.judge.table",
    "QUAT_NORM_TOL": "validation.judge.table",
}

__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())


class _CallablePackage(types.ModuleType):
    """This package's class: calling it calls :func:`validation.judge.judge.judge`."""

    def __call__(self, *args, **kwargs):
        from validation.judge.judge import judge

        return judge(*args, **kwargs)


sys.modules[__name__].__class__ = _CallablePackage
