"""``python -m socialnav``: the same as the ``socialnav`` command."""

import sys

from socialnav.cli import main

sys.exit(main())
