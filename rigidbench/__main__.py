"""``python -m rigidbench``: the same as the ``rigidbench`` command."""

from rigidbench.cli import entry

entry()
