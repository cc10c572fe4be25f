"""``python -m validation.bench [--skip-long] [--out DIR]`` is ``tumble bench``: the same options."""

from validation.bench.command import main

raise SystemExit(main())
