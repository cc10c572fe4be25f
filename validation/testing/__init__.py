"""The testing wing, as ``numpy.testing`` is to numpy: agreement as an assertion.

* :mod:`.agree`: ``assert_agree``, a scene's agreement checks as one assertion;
* :mod:`.pytest_plugin`: scene files ``test_*.toml`` as pytest items (entry point ``tumble``).
"""

from validation._lazy import lazy_exports

_PUBLIC = {
    "assert_agree": "validation.testing.agree",
}

__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
