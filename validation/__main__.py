"""``python -m validation`` is ``tumble``: the same commands, options and exit statuses."""

from validation.cli import run

run()
