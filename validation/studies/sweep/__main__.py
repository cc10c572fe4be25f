"""``python -m validation.studies.sweep [ARGS]`` is ``tumble sweep [ARGS]``: the same parser."""

import sys

from validation.cli import run

if __name__ == "__main__":
    run(["sweep", *sys.argv[1:]])
