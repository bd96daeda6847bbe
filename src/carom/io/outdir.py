"""Output directories that are written completely or not at all."""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from carom.errors import CaromError

__all__ = ["check_output", "publish", "staged_output"]


def check_output(path: str | os.PathLike[str], *, force: bool = False) -> Path:
    """Refuse ``path`` early if :func:`staged_output` would refuse it; return it as a Path."""
    target = Path(path)
    if target.exists() and not target.is_dir():
        raise CaromError(f"{target} exists and is not a directory; choose another --out")
    if target.is_dir() and any(target.iterdir()) and not force:
        raise CaromError(
            f"{target} already exists and is not empty; choose another --out, or pass --force "
            f"to replace it"
        )
    return target


@contextmanager
def staged_output(path: str | os.PathLike[str], *, force: bool = False) -> Iterator[Path]:
    """Yield a fresh temporary directory beside ``path``; move it to ``path`` on success.

    Nothing is written at ``path`` unless the block finishes: on any exception (Ctrl-C
    included) the temporary directory is removed and ``path`` is left as it was. An existing
    non-empty ``path`` is replaced only with ``force``; the swap is two renames, so ``path``
    never holds a half-written result.

    Raises
    ------
    CaromError
        ``path`` exists and is not empty (without ``force``), is a file, or its parent
        cannot be created.
    """
    target = check_output(path, force=force)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix=f".{target.name}.partial-", dir=target.parent))
        umask = os.umask(0)
        os.umask(umask)
        staging.chmod(0o777 & ~umask)  # mkdtemp makes it private; the result should not be
    except OSError as exc:
        raise CaromError(f"cannot create the output directory {target}: {exc.strerror}") from None
    try:
        yield staging
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    publish(staging, target)


def publish(staging: Path, target: Path) -> None:
    """Move the finished directory ``staging`` to ``target``, replacing what is there (the
    caller checked ``--force``) by two renames, so ``target`` is never half-written."""
    if target.exists():
        retired = Path(tempfile.mkdtemp(prefix=f".{target.name}.old-", dir=target.parent))
        target.rename(retired / target.name)
        staging.rename(target)
        shutil.rmtree(retired, ignore_errors=True)
    else:
        staging.rename(target)
