"""Another engine's run of a scene: trajectory files, judged (``tumble judge``).

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

"""

from validation._lazy import lazy_exports

_PUBLIC = {
    "COLUMNS": "validation.external.columns",
    "ColumnGroup": "validation.external.columns",
    "TrajectoryFormat": "validation.external.columns",
    "TrajectoryFileError": "validation.external.errors",
    "ExternalTrajectory": "validation.external.record",
    "read_trajectory": "validation.external.read",
    "write_trajectory": "validation.external.write",
    "judge_request": "validation.external.judge",
    "run_judge": "validation.external.judge",
    "write_pack": "validation.external.reference_pack",
    "read_pack": "validation.external.reference_pack",
    "GRID_TOL": "validation.external.table",
    "QUAT_NORM_TOL": "validation.external.table",
}

__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())

