"""The one exception type for bad user input.

Every reader and loader raises :class:`InputError` with a message that names the file (and
line or key) and what is wrong; the CLIs print it as one line on stderr and exit with code 2.
"""

from __future__ import annotations

__all__ = ["EXIT_BAD_INPUT", "InputError"]

EXIT_BAD_INPUT = 2


class InputError(Exception):
    """A problem with a user-supplied file or argument, worded for the user. Its text is one line
    whatever the input held: a line break inside it (a YAML key or value quoted into the message)
    reads as ``\\n``."""

    def __str__(self) -> str:
        return super().__str__().replace("\r", "\\r").replace("\n", "\\n")
