"""The exception a SIGINT or SIGTERM becomes in the command (`rigidbench.cli`).

A module of its own that imports nothing of rigidbench: the signal may arrive while another module is half
imported (planning starts within the first second), and the handler and `cli.main` must still be able to name it.
"""

from __future__ import annotations

import signal


class Interrupted(BaseException):
    """SIGINT or SIGTERM during a run; the exit status is 128 + the signal number."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.status = 128 + signum
        self.name = signal.Signals(signum).name
