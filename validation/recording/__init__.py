"""The recording wing: ``run.rrd`` for the Rerun viewer.

* :mod:`.recording`: ``write_recording``, the front;
* :mod:`.stream`: in-memory streams and the read-back check;
* :mod:`.world`: the 3D entities, trails and exaggerated differences;
* :mod:`.plots`: the time series;
* :mod:`.layout`: the blueprint, narrative and legend;
* :mod:`.style`: colours, application ids and viewer text;
* :mod:`.live`: the live viewer (``--spawn``, ``--connect``, ``--serve``): each plant's stream and
  the recording sent to it.
"""

from typing import TYPE_CHECKING

from validation._lazy import lazy_exports

_PUBLIC = {
    "write_recording": "validation.recording.recording",
    "RecordingInfo": "validation.recording.recording",
    "LiveViewer": "validation.recording.live",
    "watching": "validation.recording.live",
}

if TYPE_CHECKING:  # the same names, typed for a type checker (never run: imports stay lazy)
    from validation.recording.live import LiveViewer as LiveViewer
    from validation.recording.live import watching as watching
    from validation.recording.recording import RecordingInfo as RecordingInfo
    from validation.recording.recording import write_recording as write_recording

__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
