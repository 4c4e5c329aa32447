"""``python -m motosim``: the same as the ``motosim`` command."""

import sys

from motosim.cli.main import main

if __name__ == "__main__":
    sys.exit(main())
