"""``python -m meshcorr``: the same as the ``meshcorr`` console script."""

import sys

from ._console import main

sys.exit(main())
