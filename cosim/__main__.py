"""``python -m cosim``: the ``cosim`` command, for when its script is not on ``PATH``."""

import sys

from cosim.cli import main

sys.exit(main())
