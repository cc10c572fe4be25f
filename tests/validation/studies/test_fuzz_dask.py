"""The campaign and the sweep on a Dask cluster give the serial run's results (dask is in
``[test]``: this runs on every submission)."""

from __future__ import annotations

import pytest

from validation.studies.fuzz.campaign import SerialExecutor, fuzz
from validation.studies.sweep.running import executor_for

pytest.importorskip("distributed")  # in [test]; skipped only outside the project's test install

PLANTS = ("analytic", "pinocchio")


def _strip(d):
    return {k: v for k, v in d.items() if k != "walls"}


def test_dask_local_cluster_gives_the_serial_verdicts(tmp_path):
    kw = dict(budget=3, seed=3, plants=PLANTS, horizon=0.1, report=False, shrink_evaluations=5)
    serial = fuzz(tmp_path / "serial", executor=SerialExecutor(), **kw)
    dask = fuzz(tmp_path / "dask", dask_workers=2, **kw)
    assert [_strip(r.outcome.to_dict()) for r in serial.scenes] == [
        _strip(r.outcome.to_dict()) for r in dask.scenes
    ]


def test_executor_for_refuses_both_and_bad_counts():
    with pytest.raises(ValueError, match=r"^scheduler: "), executor_for(None, "tcp://x:1", 2):
        pass
    with pytest.raises(ValueError, match=r"^dask_workers: "), executor_for(None, None, 0):
        pass
