"""The studies wing: what is measured across many runs, and what is taught.

* :mod:`.sweep`: the work-precision study (``tumble sweep``): what accuracy costs in time;
* :mod:`.hard_cases`: the hard-case stability suite (``tumble hard-cases``);
* :mod:`.effects_cost`: what each effect of a scene costs per evaluation;
* :mod:`.demo`, :mod:`.demo_notebook`: the narrated teaching demo and its notebook.
"""

from typing import TYPE_CHECKING

from validation._lazy import lazy_exports

_PUBLIC = {
    "write_demo": "validation.studies.demo",
}

if TYPE_CHECKING:  # the same names, typed for a type checker (never run: imports stay lazy)
    from validation.studies.demo import write_demo as write_demo

__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
