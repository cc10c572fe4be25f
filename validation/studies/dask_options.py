"""The Dask options of ``tumble sweep`` and ``tumble fuzz`` (``--scheduler``, ``--dask-workers``),
checked before anything is started or written.

* ``dask_workers`` is a whole number from 1 to :func:`max_dask_workers` (4 per core this process
  may use): every worker of a ``LocalCluster`` is a process with its own threads, and a thousand
  of them on a small machine end minutes later in "can't start new thread" instead of running.
* ``scheduler``: a TCP address (``tcp://``, ``tls://``, ``ws://``, ``wss://`` or no scheme; port
  8786 when none is given) must accept a connection within :data:`SCHEDULER_PROBE_S` s, and a
  plain ``tcp://`` one must then send its first bytes within as long (a Dask scheduler writes its
  handshake as soon as a connection opens; Dask's own client would wait forever on a port that
  listens but says nothing); otherwise a ``ValueError`` names the address: a cluster that is not
  there is said at once, not after Dask's 30 s connect timeout. Other schemes are left to Dask.
* ``dashboard`` (``--dashboard``): the ``LocalCluster`` of ``dask_workers`` serves Dask's
  dashboard on 127.0.0.1 only (:data:`DASHBOARD_ADDRESS`; another free port when that one is
  taken, as Dask does); with ``scheduler`` the scheduler's own dashboard is the one linked. It
  needs one of the two options, and for the local cluster ``bokeh`` (``pip install
  "tumbling-testbed[dask]"``): otherwise a ``ValueError`` naming ``dashboard``. Without it the
  cluster has no dashboard.
"""

from __future__ import annotations

import os
import socket
from urllib.parse import urlsplit

WORKERS_PER_CORE = 4
"""Most ``--dask-workers`` per core this process may use."""
SCHEDULER_PROBE_S = 5.0
"""How long a scheduler's address may take to accept a TCP connection, s."""
DEFAULT_SCHEDULER_PORT = 8786
DASHBOARD_ADDRESS = "127.0.0.1:8787"
"""Where ``--dashboard`` serves the local cluster's dashboard: Dask's usual port, on the loopback
interface only (the dashboard shows the runs and has no authentication)."""
_TCP_SCHEMES = ("", "tcp", "tls", "ws", "wss")


def cores() -> int:
    """Cores this process may use (its CPU affinity where the system has one)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def max_dask_workers() -> int:
    """The most ``dask_workers`` accepted: :data:`WORKERS_PER_CORE` per core."""
    return WORKERS_PER_CORE * max(1, cores())


def check_dask_workers(dask_workers: int | None) -> None:
    """Raise ``ValueError`` naming ``dask_workers`` unless it is None or 1 .. max_dask_workers()."""
    if dask_workers is None:
        return
    if isinstance(dask_workers, bool) or not isinstance(dask_workers, int) or dask_workers < 1:
        raise ValueError(f"dask_workers: must be a whole number ≥ 1 (got {dask_workers!r})")
    if dask_workers > max_dask_workers():
        raise ValueError(
            f"dask_workers: at most {max_dask_workers()} ({WORKERS_PER_CORE} per core, "
            f"{cores()} cores here) (got {dask_workers})"
        )


def _host_port(address: str) -> tuple[str, int] | None:
    """``(host, port)`` of a TCP scheduler address, None for another scheme.

    Raises:
        ValueError: naming ``scheduler`` for an address that is not one.
    """
    text = address if "://" in address else f"tcp://{address}"
    parts = urlsplit(text)
    if parts.scheme not in _TCP_SCHEMES:
        return None
    try:
        port = parts.port
    except ValueError:
        port = -1
    if not parts.hostname or port == -1 or parts.path not in ("", "/"):
        raise ValueError(
            f"scheduler: not a Dask scheduler's address like tcp://host:8786 (got {address!r})"
        )
    return parts.hostname, port or DEFAULT_SCHEDULER_PORT


def probe_scheduler(address: str, timeout_s: float = SCHEDULER_PROBE_S) -> None:
    """Raise ``ValueError`` naming ``scheduler`` and ``address`` unless a TCP connection to it is
    accepted within ``timeout_s`` s (module docstring)."""
    if not isinstance(address, str) or not address.strip():
        raise ValueError(f"scheduler: must be an address like tcp://host:8786 (got {address!r})")
    hp = _host_port(address.strip())
    if hp is None:
        return
    plain = urlsplit(address if "://" in address else f"tcp://{address}").scheme == "tcp"
    try:
        with socket.create_connection(hp, timeout=timeout_s) as s:
            if plain and not s.recv(1):
                raise OSError("it closed the connection without a handshake")
    except OSError as exc:
        why = (
            f"no answer within {timeout_s:g} s"
            if isinstance(exc, TimeoutError)
            else (exc.strerror or str(exc))
        )
        raise ValueError(f"scheduler: no Dask scheduler answers at {address} ({why})") from None


def check_dask_options(scheduler: str | None, dask_workers: int | None) -> None:
    """Both options checked (module docstring); ``ValueError`` naming the option otherwise."""
    if scheduler is not None and dask_workers is not None:
        raise ValueError("scheduler: give either --scheduler or --dask-workers, not both")
    check_dask_workers(dask_workers)
    if scheduler is not None:
        probe_scheduler(scheduler)


def check_dashboard(dashboard: bool, scheduler: str | None, dask_workers: int | None) -> None:
    """``ValueError`` naming ``dashboard`` when it is asked for without a Dask cluster or
    without ``bokeh`` (module docstring)."""
    if not dashboard:
        return
    if scheduler is None and dask_workers is None:
        raise ValueError(
            "dashboard: shows a Dask cluster's work; give --dask-workers N or --scheduler too"
        )
    from importlib.util import find_spec

    if dask_workers is not None and find_spec("bokeh") is None:  # a scheduler serves its own
        raise ValueError(
            'dashboard: Dask\'s dashboard needs bokeh (pip install "tumbling-testbed[dask]")'
        )


def dashboard_address(dashboard: bool) -> str | None:
    """The ``dashboard_address`` of a ``LocalCluster``: :data:`DASHBOARD_ADDRESS` with
    ``dashboard``, else None (no dashboard)."""
    return DASHBOARD_ADDRESS if dashboard else None


__all__ = [
    "DASHBOARD_ADDRESS",
    "SCHEDULER_PROBE_S",
    "WORKERS_PER_CORE",
    "check_dashboard",
    "check_dask_options",
    "check_dask_workers",
    "dashboard_address",
    "max_dask_workers",
    "probe_scheduler",
]
