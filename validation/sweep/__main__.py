"""``python -m validation.sweep [ARGS]`` is ``tumble sweep [ARGS]``: the same parser."""

import sys

from validation.cli import main

if __name__ == "__main__":
    sys.exit(main(["sweep", *sys.argv[1:]]))
