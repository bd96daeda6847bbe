"""Small helpers for the words carom prints."""

from __future__ import annotations

__all__ = ["plural"]


def plural(count: int, one: str, many: str | None = None) -> str:
    """``1 collision``, ``2 collisions``; ``many`` for irregular plurals (``bodies``).

    >>> plural(1, "collision"), plural(3, "body", "bodies")
    ('1 collision', '3 bodies')
    """
    return f"{count} {one if count == 1 else (many or one + 's')}"
