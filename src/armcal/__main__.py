"""``python -m armcal``: the same program as the ``armcal`` command."""

import sys

from .cli import main

sys.exit(main())
