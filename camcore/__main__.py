"""``python3 -m camcore ...``: the ``camcore`` command (camcore.cli), for a Python whose
scripts folder is not on the PATH (a designer's review ran the README's command so)."""

import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main())
