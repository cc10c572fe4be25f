"""The fuzzer's hard time limit on one plant run (:func:`validation.studies.fuzz.judge.run_limited`)
where forking from the running process is not safe: under a thread pool and on a Dask
``LocalCluster`` of worker processes (multi-threaded, made non-daemonic), a plant that never reports
progress is still stopped at its limit, by a child of the fork server, and its process is gone."""

from __future__ import annotations

import os
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from analytic.scene.dump import scene_to_dict
from tests.support.fuzz_plants import SLEEP_S, SleepyPlant
from validation.runs import workers
from validation.scenes import resolve_scene
from validation.studies.fuzz.judge import judge_scene

needs_server = pytest.mark.skipif(
    not workers.can_serve(), reason="a fork server needs Linux and workers switched on"
)

TIME_LIMIT_S = 2.0
"""The limit each run is given, s."""
STOP_MARGIN_S = 0.25 * SLEEP_S - TIME_LIMIT_S
"""Past the limit, what stopping may take: SIGTERM, the 0.5 s grace before SIGKILL
(``workers.STOP_GRACE_S``), reaping, and on the first run the fork server's start with its
preload (about 1.5 s on the 2-core machine). A stopped run ends within a quarter of SLEEP_S, a run
that was not stopped cannot (this is the line between stopped and not stopped, not a timing
goal)."""
HORIZON_S = 0.1


def _scene_data() -> dict:
    data = scene_to_dict(resolve_scene("paper_example1_controlled"))
    data["output"]["t_end"] = HORIZON_S
    return data


def judge_timed(data, plants, budget_s):
    """``judge_scene`` and its wall time, s, with the caller's process id (the executor's task)."""
    t0 = time.perf_counter()
    out = judge_scene(data, plants, HORIZON_S, budget_s=budget_s)
    return out.to_dict(), time.perf_counter() - t0, os.getpid(), workers.can_fork()


def _assert_stopped(res, pid_dir: Path, caller_pid: int) -> None:
    out, wall, _pid, forked_here = res
    assert not forked_here  # the executor's process is multi-threaded: no fork from it
    assert out["timeouts"] == {"pinocchio": TIME_LIMIT_S}
    assert out["ran"] == ["analytic"] and out["disagreements"] == []
    assert TIME_LIMIT_S <= out["walls"]["pinocchio"] < TIME_LIMIT_S + STOP_MARGIN_S
    assert wall < TIME_LIMIT_S + STOP_MARGIN_S + 0.25 * SLEEP_S
    pids = [int(p.stem) for p in pid_dir.iterdir()]
    assert len(pids) == 1 and pids[0] != caller_pid  # the run was in its own process ...
    with pytest.raises(ProcessLookupError):  # ... which is gone (killed, not left sleeping)
        os.kill(pids[0], 0)


@needs_server
def test_a_silent_plant_is_stopped_at_its_limit_under_a_thread_pool(tmp_path):
    with ThreadPoolExecutor(1) as ex:
        res = ex.submit(
            judge_timed, _scene_data(), ["analytic", SleepyPlant(tmp_path)], TIME_LIMIT_S
        ).result()
    _assert_stopped(res, tmp_path, os.getpid())


@needs_server
def test_a_silent_plant_is_stopped_at_its_limit_on_a_dask_local_cluster(tmp_path):
    """Dask's worker processes are multi-threaded; started by hand they are made non-daemonic
    (``distributed.worker.daemon``), as documented, so that a run may go to the fork server."""
    distributed = pytest.importorskip("distributed")
    import dask

    with (
        dask.config.set({"distributed.worker.daemon": False}),
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        res = client.submit(
            judge_timed, _scene_data(), ["analytic", SleepyPlant(tmp_path)], TIME_LIMIT_S,
            pure=False,
        ).result()  # fmt: skip
    assert res[2] != os.getpid()
    _assert_stopped(res, tmp_path, res[2])
