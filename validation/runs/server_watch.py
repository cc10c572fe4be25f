"""The fork server's first preload (:func:`validation.runs.workers.start_served`): the server ends
when the process that started it does, also one killed with SIGKILL
(:func:`validation.runs.lifetime.die_with`, a watch of that process).

First, before the other preloads: those import the engines and may compile numba's kernels for
minutes (a cold or damaged cache), and until the server reaches its loop it watches nothing
(``multiprocessing``'s pipe is read only there), so a server whose client was killed during its
preload ran on to the preload's end. The client's pid comes in :data:`CLIENT_ENV` (set by
:func:`validation.runs.workers.start_served` for the server's start only), not from
``os.getppid()``: a client killed before this runs has left the server to init. Import it only
on purpose: it does its work at import.
"""

from __future__ import annotations

import os

from validation.runs.lifetime import ORPHANED_EXIT, die_with

CLIENT_ENV = "TUMBLE_FORK_SERVER_CLIENT"
"""The environment variable that names the server's client (its pid) to the server."""

_client = os.environ.pop(CLIENT_ENV, "")  # the served children need not see it
if _client.isdigit():
    if os.getppid() != int(_client):  # the client is gone already
        os._exit(ORPHANED_EXIT)
    die_with(int(_client))
