"""A fake batched plant: the analytic plant's integration, run as one batch per call.

``batched_echo`` declares ``batched = True`` and implements ``_simulate_batch`` itself
(``docs/plugins.md`` §14): every scene of the batch integrated by the analytic plant, one after the
other, each trajectory renamed and marked with its batch (``info["batch_size"]``,
``info["batch_position"]``), progress reported as the batch's common time (the smallest time its
worlds have reached). ``call_overhead_s`` is a fixed cost per call (a kernel launch, a transfer),
slept once per batch and once per single run: with it, scenes per second grow with the batch size
as they do on an accelerated engine, so a throughput measurement has something to show.
"""

from __future__ import annotations

import dataclasses
import time

from analytic.plant import AnalyticPlant


class BatchedEchoPlant(AnalyticPlant):
    """The analytic plant's motion as the plant ``batched_echo``, natively batched (module docstring)."""

    engine = "batched_echo"
    label = "Batched echo"
    default = False  # asked for by name only
    batched = True
    call_overhead_s = 0.0
    """Seconds slept once per call (module docstring)."""

    def _run(self, scene, settings, t_end, progress):
        tr = super()._simulate(scene, settings, t_end, progress)
        return dataclasses.replace(tr, engine=self.engine)

    def _simulate(self, scene, settings, t_end, progress):
        time.sleep(self.call_overhead_s)
        tr = self._run(scene, settings, t_end, progress)
        return dataclasses.replace(tr, info={**tr.info, "batch_size": 1, "batch_position": 0})

    def _simulate_batch(self, scenes, settings, t_end, progress):
        time.sleep(self.call_overhead_s)
        horizons = [t_end if t_end is not None else s.output.t_end for s in scenes]
        reached = [0.0] * len(scenes)
        out = []
        for k, (scene, horizon) in enumerate(zip(scenes, horizons, strict=True)):

            def told(t, k=k, horizon=horizon):
                reached[k] = t
                if progress is not None:
                    progress(min(reached))  # the time every world has reached

            tr = self._run(scene, settings, t_end, told)
            reached[k] = horizon
            info = {**tr.info, "batch_size": len(scenes), "batch_position": k}
            out.append(dataclasses.replace(tr, info=info))
        return out
