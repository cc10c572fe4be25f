"""MuJoCo's process-global callbacks, installed only for the duration of a ``with`` block.

On MuJoCo 4.0, Python ``mjcb_*`` callbacks are global, compiling a model
fails while one is installed, and with RK4 ``mjcb_control`` / ``mjcb_act_bias`` run at each of the
four stages (a force computed there keeps RK4 fourth order; one set once per step is first order).
:class:`installed` sets them after the model has been compiled and always removes them, also when
the body of the ``with`` raises. Nesting is refused (two twins cannot share the global slots).

MuJoCo's warnings are collected while a block steps (:class:`collapsed_warnings`), and
:func:`bad_warnings` names those after which a step is not the model's dynamics.
"""

from __future__ import annotations

import re
import threading
import warnings
from collections.abc import Callable

import mujoco

_lock = threading.Lock()
_active = False

# MuJoCo warnings after which the step is not the model's dynamics (MuJoCo resets or zeroes silently).
# Each says what MuJoCo found ("Nan, Inf or huge value", its own words: "the simulation is
# unstable") and what it did about it.
BAD_WARNINGS = {
    mujoco.mjtWarning.mjWARN_BADQPOS: "unstable: bad qpos (MuJoCo reset the state)",
    mujoco.mjtWarning.mjWARN_BADQVEL: "unstable: bad qvel (MuJoCo reset the state)",
    mujoco.mjtWarning.mjWARN_BADQACC: "unstable: bad qacc (MuJoCo reset the state)",
    mujoco.mjtWarning.mjWARN_BADCTRL: "unstable: bad ctrl (MuJoCo zeroed every control)",
}


def bad_warnings(d: mujoco.MjData) -> list[str]:
    """Descriptions of the MuJoCo warnings raised so far that invalidate the dynamics."""
    return [
        f"{w.name} x{d.warning[int(w)].number}: {text}"
        for w, text in BAD_WARNINGS.items()
        if d.warning[int(w)].number > 0
    ]


def bad_warning_counts(d: mujoco.MjData) -> list[int]:
    """The counts of :data:`BAD_WARNINGS` in ``d``, in that order."""
    return [d.warning[int(w)].number for w in BAD_WARNINGS]


def set_bad_warning_counts(d: mujoco.MjData, counts: list[int]) -> None:
    """Set the counts of :data:`BAD_WARNINGS` in ``d`` (undo those of a step that is redone)."""
    for w, k in zip(BAD_WARNINGS, counts, strict=True):
        d.warning[int(w)].number = k


def spring_user_bias(m: mujoco.MjModel, d: mujoco.MjData, i: int) -> float:
    """``mjcb_act_bias`` for the spring actuators of :mod:`model_xml.builder`: the affine part
    ``b0 + b1 L`` plus the cubic term ``b3 (L - b4)³`` (``b = actuator_biasprm[i]``), N."""
    b = m.actuator_biasprm[i]
    L = d.actuator_length[i]
    x = L - b[4]
    return float(b[0] + b[1] * L + b[2] * d.actuator_velocity[i] + b[3] * x * x * x)


class installed:
    """Context manager: ``with installed(control=f, act_bias=g): mj_step(...)``.

    Args:
        control: ``f(model, data)`` for ``mjcb_control`` or None.
        act_bias: ``g(model, data, actuator_id) -> float`` for ``mjcb_act_bias`` or None.
    """

    def __init__(
        self,
        control: Callable[[mujoco.MjModel, mujoco.MjData], None] | None = None,
        act_bias: Callable[[mujoco.MjModel, mujoco.MjData, int], float] | None = None,
    ):
        self.control = control
        self.act_bias = act_bias

    def __enter__(self) -> installed:
        global _active
        with _lock:
            if _active:
                raise RuntimeError("mj_bridge callbacks are already installed (they are global)")
            if any_installed():
                raise RuntimeError(
                    "a MuJoCo control or act-bias callback is already installed by other code; "
                    "mj_bridge will not replace it"
                )
            _active = True
        try:
            if self.control is not None:
                mujoco.set_mjcb_control(self.control)
            if self.act_bias is not None:
                mujoco.set_mjcb_act_bias(self.act_bias)
        except BaseException:
            self._remove()
            raise
        return self

    def _remove(self) -> None:
        global _active
        try:
            mujoco.set_mjcb_control(None)
            mujoco.set_mjcb_act_bias(None)
        finally:
            with _lock:
                _active = False

    def __exit__(self, *exc) -> None:
        self._remove()


# Distinct MuJoCo warnings reported after one block of stepping (one line each, with a count); the
# rest are summed in one more line. An unstable run warns at every step (340 lines for g = 1e300),
# and what they say is in the first few; the run's status says the rest.
MAX_WARNING_LINES = 3
_TIME_SUFFIX = re.compile(r"\s*Time = [-+0-9.eE]+\.?\s*$")


class collapsed_warnings:
    """Context manager: MuJoCo's warnings (``mju_user_warning``, printed by MuJoCo one per step
    otherwise) are collected while it is active and reported when it ends as Python warnings, one
    line per distinct text (its ``Time = ...`` dropped) with how often and from when, at most
    :data:`MAX_WARNING_LINES` lines plus one for the rest. Nested use collects in the outer one.
    """

    _depth = 0

    def __init__(self) -> None:
        self.seen: dict[str, list] = {}  # text -> [count, first time]
        self.previous = None

    def _handler(self, msg: str) -> None:
        text = " ".join(str(msg).split())
        m = _TIME_SUFFIX.search(text)
        key = text[: m.start()] if m else text
        first = m.group(0).strip().rstrip(".") if m else ""
        entry = self.seen.setdefault(key, [0, first])
        entry[0] += 1

    def __enter__(self) -> collapsed_warnings:
        collapsed_warnings._depth += 1
        if collapsed_warnings._depth == 1:
            self.previous = mujoco.get_mju_user_warning()
            mujoco.set_mju_user_warning(self._handler)
        return self

    def __exit__(self, *exc) -> None:
        collapsed_warnings._depth -= 1
        if collapsed_warnings._depth:
            return
        mujoco.set_mju_user_warning(self.previous)
        items = list(self.seen.items())
        for text, (count, first) in items[:MAX_WARNING_LINES]:
            times = f"{count} times, first at {first}" if count > 1 else first or "once"
            warnings.warn(f"MuJoCo: {text} ({times})", UserWarning, stacklevel=2)
        rest = items[MAX_WARNING_LINES:]
        if rest:
            n = sum(c for _, (c, _) in rest)
            warnings.warn(
                f"MuJoCo: {n} more warnings of {len(rest)} other kinds", UserWarning, stacklevel=2
            )
        self.seen.clear()


def any_installed() -> bool:
    """Whether a MuJoCo control or act-bias callback is currently set (any source)."""
    return mujoco.get_mjcb_control() is not None or mujoco.get_mjcb_act_bias() is not None
