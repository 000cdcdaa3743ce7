"""``python -m rigidbench``: the same as the ``rigidbench`` command."""

import sys

from rigidbench.cli import main

sys.exit(main())
