"""The exception carom raises for bad input, and its one warning."""

from __future__ import annotations

__all__ = ["CaromError", "CaromWarning"]


class CaromError(ValueError):
    """Invalid input: the message names the argument, the offending value and the fix.

    A subclass of :class:`ValueError`, so ``except ValueError`` catches it too.
    """


class CaromWarning(UserWarning):
    """Something the user should know that does not stop the work (a full in-memory log)."""
