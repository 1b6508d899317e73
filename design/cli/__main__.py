"""``python -m design.cli``: the ``etorigami`` command."""

import sys

from . import main

if __name__ == "__main__":
    sys.exit(main())
