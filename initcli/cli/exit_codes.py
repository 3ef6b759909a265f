"""The exit codes of ``bim-init match`` (and of every command that reports a match): the one place a
match's outcome becomes a code.

0 unique match, 3 ambiguous (several hypotheses), 4 no consistent match; 2 bad input, the code of
every command's bad input (:data:`bimkit.errors.EXIT_BAD_INPUT`, exported here as well).
"""

from __future__ import annotations

from bimkit.errors import EXIT_BAD_INPUT
from initcli.core.hypotheses.ranking import Verdict

__all__ = ["EXIT_AMBIGUOUS", "EXIT_BAD_INPUT", "EXIT_NO_MATCH", "EXIT_UNIQUE", "match_exit_code"]

EXIT_UNIQUE = 0
EXIT_AMBIGUOUS = 3
EXIT_NO_MATCH = 4

_MATCH_EXIT = {Verdict.UNIQUE: EXIT_UNIQUE, Verdict.AMBIGUOUS: EXIT_AMBIGUOUS, Verdict.NONE: EXIT_NO_MATCH}


def match_exit_code(outcome: Verdict) -> int:
    """The exit code of a match whose outcome is ``outcome``."""
    return _MATCH_EXIT[outcome]
