"""The side-by-side validation of the analytic plant and the MuJoCo twin, and the ``tumble`` CLI.

Importing this package sets ``NO_COLOR=1`` when stderr is not a terminal (unless ``NO_COLOR`` is
set already): Rerun's logger otherwise writes ANSI colour codes into files and pipes. It reads the
variable once, when ``rerun`` is first imported, which in this project happens inside this package
(:mod:`validation.recording`).
"""

import os as _os

if "NO_COLOR" not in _os.environ and not _os.isatty(2):
    _os.environ["NO_COLOR"] = "1"
