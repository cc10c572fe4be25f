"""``python -m validation`` is ``tumble``: the same commands, options and exit statuses."""

import sys

from validation.cli import main

sys.exit(main())
