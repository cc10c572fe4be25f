"""The hard-case table: one row per case, a column per plant; written as ``hard_cases.md`` and
``hard_cases.json`` (each atomically, :mod:`validation.runs.atomic`; ``hard_cases.html`` beside
them: :mod:`validation.studies.hard_cases.html_report`).

A row's checks are the comparison's :class:`validation.compare.checks.Check` records: a check about one
plant has that plant as its subject, a check against the analytic plant the pair (it belongs to
the plant compared). In ``hard_cases.json`` every number is a JSON number, and a value that is not
finite (a NaN, an infinity: an event that did not happen, a run that blew up) is ``null``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import Enum, StrEnum
from pathlib import Path
from typing import Any

import numpy as np

from analytic.effects import Precision
from analytic.trajectory import Engine
from validation.compare.checks import Check
from validation.report.provenance import FileKind, dumps, provenance
from validation.runs.atomic import write_text
from validation.studies.hard_cases.judgeable import NotJudgeable
from validation.studies.hard_cases.measures import ANALYTIC, label
from validation.studies.roundoff import EPS

JSON_NAME = "hard_cases.json"
MARKDOWN_NAME = "hard_cases.md"


class Verdict(StrEnum):
    """A case's verdict, or a plant's within a case."""

    PASS = "PASS"
    FAIL = "FAIL"
    """A check failed."""
    ERROR = "ERROR"
    """The case raised (or judged nothing on a plant it ran on)."""
    NA = "N/A"
    """The case does not apply to the plant (said why)."""
    NOT_JUDGEABLE = "not judgeable"
    """Every bound of the case on the plant is below its precision's round-off
    (:mod:`validation.studies.roundoff`): neither a PASS nor a FAIL."""


def owner(check: Check) -> str:
    """The plant a check judges: its subject, or of a pair the plant compared with the analytic
    one."""
    plants = check.subject.plants
    return next((p for p in plants if p != ANALYTIC), plants[0]) if len(plants) > 1 else plants[0]


@dataclass(frozen=True)
class Reported:
    """A figure reported, not judged (a ``[[hard_case.report]]`` entry), on one plant."""

    plant: str
    name: str
    value: float
    unit: str
    why: str

    def to_dict(self) -> dict[str, Any]:
        return {
            "plant": self.plant,
            "name": self.name,
            "value": self.value,
            "unit": self.unit,
            "why": self.why,
        }


@dataclass(frozen=True)
class HardCaseRow:
    """One hard case.

    Attributes:
        case: scene name without ``hard/``.
        criterion: the scene's stated criterion (``[hard_case] criterion``).
        plants: the plants of the suite, in report order.
        figures: plant -> figures (name -> number, or text such as a status) for each plant the
            case ran on.
        checks: every judged figure with its bound (:class:`validation.compare.checks.Check`).
        verdict: PASS, FAIL (a check failed) or ERROR (the case raised).
        wall_time_s: wall time of the whole case.
        notes: findings reported but not judged (crossings, solver costs, a failed check's note).
        not_applicable: plant -> why the case does not apply to it.
        error: the exception of an ERROR row.
        reported: figures reported, not judged.
        not_judgeable: the checks below a plant's precision's round-off (made with
            ``applicable = False``: they pass nothing and fail nothing).
        precisions: plant -> the precision it ran in (float64 unless its settings say).
    """

    case: str
    criterion: str
    plants: tuple[str, ...]
    figures: Mapping[str, dict[str, Any]]
    checks: tuple[Check, ...]
    verdict: Verdict
    wall_time_s: float
    notes: tuple[str, ...] = ()
    not_applicable: Mapping[str, str] = field(default_factory=dict)
    error: str = ""
    reported: tuple[Reported, ...] = ()
    not_judgeable: tuple[NotJudgeable, ...] = ()
    precisions: Mapping[str, Precision] = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        return self.verdict is Verdict.PASS

    def unjudged(self, plant: str) -> list[NotJudgeable]:
        """The checks of ``plant`` its precision cannot judge."""
        return [x for x in self.not_judgeable if x.plant == plant]

    def plant_verdict(self, plant: str) -> Verdict:
        """PASS / FAIL from ``plant``'s checks, N/A where the case does not apply, ERROR when the
        case raised or judged nothing on it."""
        if plant in self.not_applicable:
            return Verdict.NA
        if self.verdict is Verdict.ERROR:
            return Verdict.ERROR
        own = [c for c in self.checks if owner(c) == plant]
        if not own:
            return Verdict.ERROR  # a plant the case ran on without judging it: a bug of the case
        if not all(c.passed for c in own):
            return Verdict.FAIL
        unjudged = {x.check for x in self.unjudged(plant)}
        bounded = [c for c in own if c.bound]
        if unjudged and all(c.label in unjudged for c in bounded):
            return Verdict.NOT_JUDGEABLE  # nothing beyond completed / finite could be judged
        return Verdict.PASS

    def failed_checks(self, plant: str | None = None) -> list[Check]:
        return [c for c in self.checks if not c.passed and (plant is None or owner(c) == plant)]

    def to_dict(self) -> dict[str, Any]:
        per_plant: dict[str, Any] = {}
        for e in self.plants:
            entry: dict[str, Any] = {"verdict": self.plant_verdict(e).value}
            if e in self.not_applicable:
                entry["not applicable"] = self.not_applicable[e]
            else:
                if e in self.precisions:
                    entry["precision"] = Precision(self.precisions[e]).value
                entry["figures"] = dict(self.figures.get(e, {}))
                failed = [c.label for c in self.failed_checks(e)]
                if failed:
                    entry["failed"] = failed
                unjudged = self.unjudged(e)
                if unjudged:
                    entry["not judgeable"] = [x.check for x in unjudged]
            per_plant[e] = entry
        verdicts = {x.check: x.to_dict()["verdict"] for x in self.not_judgeable}
        return {
            "case": self.case,
            "criterion": self.criterion,
            "verdict": self.verdict.value,
            "plants": per_plant,
            "checks": [
                {
                    "label": c.label,
                    "plant": owner(c),
                    **c.to_dict(),
                    **(
                        {"verdict": verdicts[c.label], "judgeable": False}
                        if c.label in verdicts
                        else {"judgeable": True}
                    ),
                }
                for c in self.checks
            ],
            "not_judgeable": [x.to_dict() for x in self.not_judgeable],
            "reported": [r.to_dict() for r in self.reported],
            "wall_time_s": self.wall_time_s,
            "notes": list(self.notes),
            "error": self.error,
        }


@dataclass(frozen=True)
class HardCaseTable:
    """The table of :func:`validation.studies.hard_cases.run_hard_cases`; ``passed`` when every row
    passed.

    Attributes:
        rows: one per case run.
        complete, message: False and why when the suite stopped early.
        plants: the plants every case ran on (report order).
        not_installed: plant -> why it is not installed (it ran on no case).
    """

    rows: tuple[HardCaseRow, ...]
    complete: bool = True
    message: str = ""
    plants: tuple[str, ...] = (Engine.ANALYTIC.value, Engine.MUJOCO.value)
    not_installed: Mapping[str, str] = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        return self.complete and all(r.passed for r in self.rows)

    def row(self, case: str) -> HardCaseRow:
        for r in self.rows:
            if r.case == case:
                return r
        raise KeyError(case)

    def to_dict(self) -> dict[str, Any]:
        return {
            "passed": self.passed,
            "complete": self.complete,
            "message": self.message,
            "plants": list(self.plants),
            "not_installed": dict(self.not_installed),
            "rows": [r.to_dict() for r in self.rows],
        }

    def to_markdown(self) -> str:
        head = "PASSED" if self.passed else "FAILED"
        ran = ", ".join(label(e) for e in self.plants)
        lines = [
            f"# Hard cases: {head}",
            "",
            f"{sum(r.passed for r in self.rows)} of {len(self.rows)} cases passed"
            + ("" if self.complete else f"; INCOMPLETE: {self.message}")
            + ".",
            "",
            f"Plants: {ran}."
            + "".join(
                f" {label(e)} was not run: not installed ({_md(why)})."
                for e, why in self.not_installed.items()
            ),
            "",
        ]
        if any(r.not_judgeable for r in self.rows):
            lines += [
                "A check whose bound is below the plant's floating-point round-off for the "
                "quantity (bound < eps x its magnitude: eps 1.19e-7 in float32) is **not "
                "judgeable** at that precision: neither a PASS nor a FAIL (docs/hard_cases.md).",
                "",
            ]
        lines += [
            "| case | criterion | "
            + " | ".join(label(e) for e in self.plants)
            + " | verdict | wall s |",
            "|---|---|" + "---|" * len(self.plants) + "---|---|",
        ]
        for r in self.rows:
            cells = []
            for e in self.plants:
                v = r.plant_verdict(e)
                if v is Verdict.NA:
                    cells.append(f"n/a: {_md(r.not_applicable[e])}")
                elif r.verdict is Verdict.ERROR:
                    cells.append(f"**{v.value}**")
                else:
                    cells.append(f"**{_cell_verdict(r, e, v)}**<br>{_figs(r.figures.get(e, {}))}")
            err = f"<br>{_md(r.error)}" if r.error else ""
            lines.append(
                f"| {r.case} | {_md(r.criterion)} | {' | '.join(cells)} "
                f"| **{r.verdict.value}**{err} | {r.wall_time_s:.1f} |"
            )
        lines += ["", "## Checks", ""]
        for r in self.rows:
            lines.append(f"### {r.case}: {r.verdict.value}")
            lines.append("")
            if r.error:
                lines.append(f"- error: {_md(r.error)}")
            for e, why in r.not_applicable.items():
                lines.append(f"- {label(e)}: not applicable: {_md(why)}")
            unjudged = {x.check: x for x in r.not_judgeable}
            for c in r.checks:
                mark = "ok" if c.passed else "FAIL"
                bound = f"bound {c.bound} = {c.threshold:.1e}" if c.bound else "must be 0"
                if c.name.startswith("completed"):
                    bound = f"horizon {c.threshold:g} s"
                if c.label in unjudged:
                    x = unjudged[c.label]
                    u = "" if c.unit == "1" else f" {c.unit}"
                    lines.append(
                        f"- not judgeable at {x.precision.value}: {c.label} = {c.value:.3e}{u} "
                        f"({bound}; {x.precision.value} round-off {x.round_off:.1e}{u} = eps "
                        f"{EPS[x.precision]:.3g} x {x.scale:.3g}{u})"
                    )
                    continue
                lines.append(f"- {mark}: {c.label} = {c.value:.3e} {c.unit} ({bound})")
            for x in r.reported:
                lines.append(
                    f"- reported: {x.plant}.{x.name} = {x.value:.3e} {x.unit} ({_md(x.why)})"
                )
            for n in r.notes:
                lines.append(f"- note: {_md(n)}")
            lines.append("")
        return "\n".join(lines)


def _cell_verdict(r: HardCaseRow, plant: str, v: Verdict) -> str:
    """A plant's verdict in the table: with its precision when a check of it was below round-off
    (``not judgeable at float32``; ``PASS (2 checks not judgeable at float32)``)."""
    unjudged = r.unjudged(plant)
    if not unjudged:
        return v.value
    p = unjudged[0].precision.value
    if v is Verdict.NOT_JUDGEABLE:
        return f"not judgeable at {p}"
    n = len(unjudged)
    return f"{v.value} ({n} check{'s' if n > 1 else ''} not judgeable at {p})"


def _md(s: str) -> str:
    return str(s).replace("|", "\\|").replace("\n", " ")


def _fmt(v: Any) -> str:
    if v is None:
        return "—"
    if isinstance(v, float):
        return f"{v:.3g}"
    return str(v)


def _figs(d: Mapping[str, Any]) -> str:
    return "<br>".join(f"{_md(k)} {_md(_fmt(v))}" for k, v in d.items()) or "—"


def jsonable(o: Any) -> Any:
    """``o`` with numbers as JSON numbers: numpy scalars as Python ones, a non-finite float as
    None (JSON ``null``), enums by value; ``TypeError`` for anything else that is not JSON (no
    placeholder text)."""
    if isinstance(o, Enum):
        return o.value
    if isinstance(o, np.generic):
        o = o.item()
    if isinstance(o, float):
        return o if math.isfinite(o) else None
    if o is None or isinstance(o, str | int | bool):
        return o
    if isinstance(o, Mapping):
        return {str(k): jsonable(v) for k, v in o.items()}
    if isinstance(o, list | tuple):
        return [jsonable(v) for v in o]
    raise TypeError(f"hard_cases.json: cannot write a {type(o).__name__} ({o!r})")


def write_json(table: HardCaseTable, out_dir: str | Path) -> Path:
    """``hard_cases.json`` in ``out_dir``, atomically: the one place the table's JSON is made."""
    doc = {"provenance": provenance(FileKind.HARD_CASES), **jsonable(table.to_dict())}
    text = dumps(doc)
    return write_text(Path(out_dir) / JSON_NAME, text)


def write_table(table: HardCaseTable, out_dir: str | Path) -> None:
    """``hard_cases.md`` and ``hard_cases.json`` in ``out_dir``, each written atomically."""
    write_json(table, out_dir)
    write_text(Path(out_dir) / MARKDOWN_NAME, table.to_markdown() + "\n")


__all__ = [
    "JSON_NAME",
    "MARKDOWN_NAME",
    "HardCaseRow",
    "HardCaseTable",
    "Reported",
    "Verdict",
    "jsonable",
    "owner",
    "write_json",
    "write_table",
]
