"""The hard-case suite: what the testbed survives, as a table.

Each case is a scene file in ``validation/scenes/hard/`` that carries its criterion as data: the
``[hard_case]`` table says what is checked, against which reference, with which named bound of its
``[thresholds]`` and why (``docs/hard_cases.md``). A case runs on every installed plant
(:func:`mj_bridge.plants.installed_plants`: the analytic plant, MuJoCo and, with ``pin``,
Pinocchio), each through the plant protocol, and ends as one row: the criterion, each plant's
figures and verdict, the case's verdict and wall time.

* :mod:`.catalogue`: what may be measured against which reference (the closed set a file names);
* :mod:`.criterion`: the ``[hard_case]`` format, read and validated (nothing in it is evaluated);
* :mod:`.references`: the independent references, one module per kind;
* :mod:`.measures`: what each measure computes on a case's runs;
* :mod:`.runner`: the one runner (``tumble hard-cases``, ``python -m validation hard-cases`` and
  ``tests/validation/studies/test_hard_cases.py``), judging with the comparison's checks (:mod:`validation.compare.checks`);
* :mod:`.table`: the table, ``hard_cases.md`` and ``hard_cases.json``.
"""

from validation.scenes import SCENES_DIR
from validation.studies.hard_cases import references
from validation.studies.hard_cases.catalogue import Measure, Reference
from validation.studies.hard_cases.criterion import Criterion, parse_criterion
from validation.studies.hard_cases.measures import label, run_plant
from validation.studies.hard_cases.runner import (
    HARD_DIR,
    HardCase,
    case_names,
    cases,
    load_case,
    run_case,
    run_hard_cases,
    suite_plants,
)
from validation.studies.hard_cases.table import (
    HardCaseRow,
    HardCaseTable,
    Verdict,
    owner,
    write_json,
    write_table,
)

PASS, FAIL, ERROR, NA = Verdict.PASS, Verdict.FAIL, Verdict.ERROR, Verdict.NA

__all__ = [
    "ERROR",
    "FAIL",
    "HARD_DIR",
    "NA",
    "PASS",
    "SCENES_DIR",
    "Criterion",
    "HardCase",
    "HardCaseRow",
    "HardCaseTable",
    "Measure",
    "Reference",
    "Verdict",
    "case_names",
    "cases",
    "label",
    "load_case",
    "owner",
    "parse_criterion",
    "references",
    "run_case",
    "run_hard_cases",
    "run_plant",
    "suite_plants",
    "write_json",
    "write_table",
]
