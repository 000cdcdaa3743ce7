"""The command line's exit statuses and its usage error, shared by `rigidbench.cli` and every verb
(`rigidbench.commands`), so that neither imports the other for them.

Exit status (README "CI"): 0 when every check passed; 1 when any check failed, a simulation diverged or a case
raised an error (each in its row); 2 for bad usage, a parameter set outside the theory's domain, an output that
cannot be written or a journal that cannot be used (one line on stderr naming it, no traceback); 130 when
interrupted by Ctrl-C (SIGINT), 143 by SIGTERM.
"""

from __future__ import annotations

EXIT_OK, EXIT_FAIL, EXIT_USAGE = 0, 1, 2


class UsageError(Exception):
    """Bad command-line input; reported in one line with exit status 2."""
