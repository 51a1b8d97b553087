"""``python -m empathy_zoo.cli``: the ``empathy-zoo`` command line."""

import sys

from empathy_zoo.cli import main

sys.exit(main())
