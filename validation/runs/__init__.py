"""The runs wing: how a command's work is carried out and kept.

* :mod:`.outputs`: output directories (one run, whole; ownership proven by a manifest);
  its parts :mod:`.paths` (slugs, default paths, run ids), :mod:`.manifest` (ownership),
  :mod:`.locks` (one run at a time) and :mod:`.staging` (staging and commit);
* :mod:`.atomic`: atomic writes;
* :mod:`.stages`: the executor of a job's stages (its plants, :mod:`.plant_runs`, and the helpers
  that make its evidence), in worker processes (:mod:`.workers`, their side :mod:`.child`, their
  :mod:`.priority`, :mod:`.time_limit`) or here;
* :mod:`.ordered`: work submitted ahead to an executor and taken back in index order;
* :mod:`.interrupts`: Ctrl-C and SIGTERM, kept until a safe point;
* :mod:`.progress`: progress with counts and an ETA (:mod:`.counter`), shown as the display
  policy says (:mod:`.display`: bars, plain lines or nothing); :mod:`.messages`: the command
  line's log handler and ``--quiet``;
* :mod:`.warmup`: the one-time numba compile (``tumble warmup``).
"""

from typing import TYPE_CHECKING

from validation._lazy import lazy_exports

_PUBLIC = {
    "output_run": "validation.runs.outputs",
    "default_out_dir": "validation.runs.outputs",
    "OutputError": "validation.runs.atomic",
    "write_bytes": "validation.runs.atomic",
    "write_text": "validation.runs.atomic",
    "Progress": "validation.runs.progress",
    "StageProgress": "validation.runs.progress",
    "warm_up": "validation.runs.warmup",
    "warming": "validation.runs.warmup",
}

if TYPE_CHECKING:  # the same names, typed for a type checker (never run: imports stay lazy)
    from validation.runs.atomic import OutputError as OutputError
    from validation.runs.atomic import write_bytes as write_bytes
    from validation.runs.atomic import write_text as write_text
    from validation.runs.outputs import default_out_dir as default_out_dir
    from validation.runs.outputs import output_run as output_run
    from validation.runs.progress import Progress as Progress
    from validation.runs.progress import StageProgress as StageProgress
    from validation.runs.warmup import warm_up as warm_up
    from validation.runs.warmup import warming as warming

__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
