"""The testing wing, as ``numpy.testing`` is to numpy: agreement as an assertion.

* :mod:`.agree`: ``assert_agree``, a scene's agreement checks as one assertion;
* :mod:`.pytest_plugin`: scene files ``test_*.toml`` as pytest items (entry point ``tumble``);
  its parts :mod:`.session_runs` (each scene run once per session, shared between xdist
  workers) and :mod:`.plugin_bench` (what the plugin costs a pytest run, measured by hand).
"""

from typing import TYPE_CHECKING

from validation._lazy import lazy_exports

_PUBLIC = {
    "assert_agree": "validation.testing.agree",
}

if TYPE_CHECKING:  # the same names, typed for a type checker (never run: imports stay lazy)
    from validation.testing.agree import assert_agree as assert_agree

__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
