"""The comparison wing: differences between N plants' trajectories, each plant judged against the
closed-form tracking laws and its balances, the named thresholds, and the referee.

* :mod:`.checks`: ``compare_plants`` (every pair's difference series and every plant's checks) and
  the ``Check`` record;
* :mod:`.thresholds`: ``thresholds_for``, the named agreement thresholds of a scene;
* :mod:`.referee`: ``referee``, which plant is the outlier of each quantity;
* :mod:`.summary`: one-line sentences and drift figures for reports and the console.
"""

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

__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
