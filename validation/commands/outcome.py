"""The closing lines of ``tumble validate`` and ``tumble judge``, and their exit status: the
verdict with its count, a failed run, each failed check, the reasons a file was not judged, every
referee ruling other than agree, and the report and recording written."""

from __future__ import annotations

from typing import Any

from validation.commands import EXIT_FAILED

CLOSING_FILES = (("report", "report.md"), ("in a browser", "report.html"), ("recording", "run.rrd"))
"""The files the closing line names, each only when the run wrote it."""


def print_outcome(res: Any, subject: str, idle_words: str, not_judged: bool = False) -> int:
    """Print the closing lines of the run ``res`` (a ``ValidationResult``) of ``subject``
    (``idle_words`` names the checks left out of the count; ``not_judged``: also say why checks
    were not judged); 0 when it passed, else :data:`~validation.commands.EXIT_FAILED`."""
    from validation.compare.referee import VerdictKind
    from validation.compare.summary import check_sentence

    counted = [c for c in res.checks if c.applicable]
    n_fail = sum(1 for c in counted if not c.passed)
    idle = len(res.checks) - len(counted)
    verdict = "PASS" if res.passed else "FAIL"
    na = f" ({idle} {idle_words})" if idle else ""
    print(f"{verdict}: {len(counted) - n_fail}/{len(counted)} checks passed{na} for {subject}")
    if res.failure:
        print(f"  run failed: {res.failure}")
    for c in res.checks:
        if not c.passed:
            print(f"  failed: {check_sentence(c, reason=False)}")
    if not_judged:
        for why in sorted({c.reason for c in res.checks if c.reason.startswith("not judged")}):
            print(f"  {why}")
    for v in res.verdicts:
        if v.kind is not VerdictKind.AGREE:
            print(f"  referee: {v.text}")
    named = [f"{what}: {res.files[name]}" for what, name in CLOSING_FILES if name in res.files]
    print("  ".join(named))
    return 0 if res.passed else EXIT_FAILED
