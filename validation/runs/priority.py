"""A process's CPU priority: idle (Linux ``SCHED_IDLE``, run only on a CPU nothing else wants) or
the one the command started with.

A stage that only prepares (a worker importing matplotlib while the plants run) is put at idle
priority so the plants keep the CPUs, and back at the normal one once it has work to do. Where
there are no scheduling policies, where the switch is refused, or where the command started idle
already, every call here leaves the priority as it is.
"""

from __future__ import annotations

import os


def _policy() -> int | None:
    """This process's scheduling policy (None where there are none to set)."""
    try:
        return os.sched_getscheduler(0)
    except (AttributeError, OSError):
        return None


_START_POLICY = _policy()
"""The policy the command started with (``SCHED_OTHER`` normally): what idle stages return to."""


def set_idle(idle: bool, pid: int = 0) -> None:
    """Process ``pid`` (0: this one) to Linux ``SCHED_IDLE`` or back to the policy the command
    started with (module docstring)."""
    if _START_POLICY is None or _START_POLICY == getattr(os, "SCHED_IDLE", None):
        return
    try:
        policy = os.SCHED_IDLE if idle else _START_POLICY
        os.sched_setscheduler(pid, policy, os.sched_param(0))
    except (AttributeError, OSError):
        pass


__all__ = ["set_idle"]
