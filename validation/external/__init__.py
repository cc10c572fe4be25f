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

from typing import TYPE_CHECKING

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

if TYPE_CHECKING:  # the same names, typed for a type checker (never run: imports stay lazy)
    from validation.external.columns import COLUMNS as COLUMNS
    from validation.external.columns import ColumnGroup as ColumnGroup
    from validation.external.columns import TrajectoryFormat as TrajectoryFormat
    from validation.external.errors import TrajectoryFileError as TrajectoryFileError
    from validation.external.judge import judge_request as judge_request
    from validation.external.judge import run_judge as run_judge
    from validation.external.read import read_trajectory as read_trajectory
    from validation.external.record import ExternalTrajectory as ExternalTrajectory
    from validation.external.reference_pack import read_pack as read_pack
    from validation.external.reference_pack import write_pack as write_pack
    from validation.external.table import GRID_TOL as GRID_TOL
    from validation.external.table import QUAT_NORM_TOL as QUAT_NORM_TOL
    from validation.external.write import write_trajectory as write_trajectory

__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
