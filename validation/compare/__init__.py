"""The comparison wing: differences between N plants' trajectories, each plant judged against the
closed-form tracking laws and its balances, the named thresholds, and the referee.

* :mod:`.checks`: ``compare_plants`` (every pair's difference series and every plant's checks) and
  the records every output serialises (``Check``, ``Series``, ``Comparison``);
* :mod:`.subject`: whose quantity a series or check is (a plant, a pair), in report order;
* :mod:`.differences`: what two plants' difference is, and the scale of its bound;
* :mod:`.tracking_laws`: the closed-form error dynamics (Eqs. 78, 84);
* :mod:`.balances`: the balances of energy and momenta, from each plant's terms;
* :mod:`.reductions`: a vector per sample to a scalar, a run to its largest magnitude;
* :mod:`.thresholds`: ``thresholds_for``, the named agreement thresholds of a scene;
* :mod:`.referee`: ``referee``, which plant is the outlier of each quantity; :mod:`.noise_floor`,
  the distance below which differences decide nothing;
* :mod:`.summary`: one-line sentences and drift figures for reports and the console.
"""

from typing import TYPE_CHECKING

from validation._lazy import lazy_exports

_PUBLIC = {
    "Check": "validation.compare.checks",
    "CheckState": "validation.compare.checks",
    "Comparison": "validation.compare.checks",
    "compare_plants": "validation.compare.checks",
    "Verdict": "validation.compare.referee",
    "VerdictKind": "validation.compare.referee",
    "Threshold": "validation.compare.thresholds",
    "thresholds_for": "validation.compare.thresholds",
    "check_sentence": "validation.compare.summary",
    "drift_figures": "validation.compare.summary",
    "summary_table": "validation.compare.summary",
}

if TYPE_CHECKING:  # the same names, typed for a type checker (never run: imports stay lazy)
    from validation.compare.checks import Check as Check
    from validation.compare.checks import CheckState as CheckState
    from validation.compare.checks import Comparison as Comparison
    from validation.compare.checks import compare_plants as compare_plants
    from validation.compare.referee import Verdict as Verdict
    from validation.compare.referee import VerdictKind as VerdictKind
    from validation.compare.summary import check_sentence as check_sentence
    from validation.compare.summary import drift_figures as drift_figures
    from validation.compare.summary import summary_table as summary_table
    from validation.compare.thresholds import Threshold as Threshold
    from validation.compare.thresholds import thresholds_for as thresholds_for

__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
