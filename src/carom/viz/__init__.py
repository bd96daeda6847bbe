"""Figures, animations and viewers (the ``viz`` extra: ``pip install 'carom[viz]'``)."""

from __future__ import annotations

from carom.errors import CaromError

__all__ = ["require_matplotlib"]


def require_matplotlib() -> None:
    """Raise a :class:`CaromError` that says how to install matplotlib when it is missing."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise CaromError(
            "figures need matplotlib: install the viz extra, pip install 'carom[viz]'"
        ) from None
