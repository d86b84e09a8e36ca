"""``python -m scoutsim``: the same as the ``scoutsim`` console script."""

from .cli import console_main

if __name__ == "__main__":
    console_main()
