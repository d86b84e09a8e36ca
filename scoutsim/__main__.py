"""``python -m scoutsim``: the same as the ``scoutsim`` console script."""

import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main())
