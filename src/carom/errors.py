"""The one exception type carom raises for bad input."""

from __future__ import annotations

__all__ = ["CaromError"]


class CaromError(ValueError):
    """Invalid input: the message names the argument, the offending value and the fix.

    A subclass of :class:`ValueError`, so ``except ValueError`` catches it too.
    """
