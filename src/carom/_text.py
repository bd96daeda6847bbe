"""Small helpers for the words carom prints."""

from __future__ import annotations

import unicodedata

__all__ = ["plural", "printable"]


def plural(count: int, one: str, many: str | None = None) -> str:
    """``1 collision``, ``2 collisions``; ``many`` for irregular plurals (``bodies``).

    >>> plural(1, "collision"), plural(3, "body", "bodies")
    ('1 collision', '3 bodies')
    """
    return f"{count} {one if count == 1 else (many or one + 's')}"


#: Unicode categories that a terminal may act on rather than show: control characters (ESC
#: starts the sequences that clear or recolour a terminal), format characters (U+202E turns
#: the text that follows around), line and paragraph separators, surrogates, private use and
#: unassigned code points
_HIDDEN = {"Cc", "Cf", "Zl", "Zp", "Cs", "Co", "Cn"}


def printable(text: str, *, one_line: bool = False) -> str:
    r"""``text`` with every character a terminal could act on written as an escape.

    Newlines and tabs are kept (with ``one_line``, a newline is written ``\n`` too: an error
    message is one line, whatever file name it quotes); anything else that is not shown as
    itself becomes ``\xNN``, ``\uNNNN`` or ``\UNNNNNNNN``, so that a scene's keys or a file
    name echoed in a message cannot clear, recolour or reorder the user's terminal.

    >>> printable("ok\x1b[2J\u202e")
    'ok\\x1b[2J\\u202e'
    >>> printable("a\nb.toml: no such file", one_line=True)
    'a\\nb.toml: no such file'
    """
    if text.isprintable():
        return text
    kept = "\t" if one_line else "\n\t"
    out = []
    for c in text:
        if c == "\n" and one_line:
            out.append("\\n")
        elif c in kept or unicodedata.category(c) not in _HIDDEN:
            out.append(c)
        elif ord(c) < 0x100:
            out.append(f"\\x{ord(c):02x}")
        elif ord(c) < 0x10000:
            out.append(f"\\u{ord(c):04x}")
        else:
            out.append(f"\\U{ord(c):08x}")
    return "".join(out)
