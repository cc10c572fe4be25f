"""The judge wing's file layer: another engine's run of a scene as a trajectory file.

* :mod:`.columns`: the column schema, declared once (name, unit, frame, group, per mass);
* :mod:`.read`: ``read_trajectory`` (CSV or Parquet -> ``ExternalTrajectory``, every bad file one
  line naming the row and column);
* :mod:`.write`: ``write_trajectory`` (a plant's ``Trajectory`` -> a file, full precision, atomic);
* :mod:`.record`: the ``ExternalTrajectory`` record and the quaternion sign convention;
* :mod:`.table`, :mod:`.csv_text`, :mod:`.parquet_table`, :mod:`.errors`: the checks, the two
  encodings and the error.

The format is documented for people writing such files in ``docs/trajectory-format.md``.
"""

from validation._lazy import lazy_exports

_PUBLIC = {
    "COLUMNS": "validation.judge.columns",
    "ColumnGroup": "validation.judge.columns",
    "TrajectoryFormat": "validation.judge.columns",
    "TrajectoryFileError": "validation.judge.errors",
    "ExternalTrajectory": "validation.judge.record",
    "read_trajectory": "validation.judge.read",
    "write_trajectory": "validation.judge.write",
    "GRID_TOL": "validation.judge.table",
    "QUAT_NORM_TOL": "validation.judge.table",
}

__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
