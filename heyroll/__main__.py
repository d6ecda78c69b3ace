"""``python -m heyroll``: the same command line as the ``heyroll`` script (heyroll.interfaces.cli)."""

import sys

from heyroll.interfaces.cli import main

if __name__ == "__main__":
    sys.exit(main())
