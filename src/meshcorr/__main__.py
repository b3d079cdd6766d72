"""``python -m meshcorr``: the same as the ``meshcorr`` console script."""

import sys

from .cli import main

sys.exit(main())
