"""``python -m mechatron``: the ``mechatron`` command (see :mod:`mechatron.cli`)."""

import sys

from mechatron.cli import main

if __name__ == "__main__":
    sys.exit(main())
