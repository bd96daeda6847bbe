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
    text = os.fspath(path)
    target = Path(path)
    if not text.strip() or target.name in ("", ".", ".."):
        raise CaromError(
            f"--out {text!r} does not name a directory of its own; results go to a new "
            f"directory that is put in place when the run is done: name one, e.g. --out results"
        )
    here = Path.cwd().resolve()
    resolved = target.resolve()
    if resolved == here or resolved in here.parents or resolved == resolved.parent:
        raise CaromError(
            f"--out {text} is the current directory or contains it; results go to a new "
            f"directory that is put in place when the run is done: name one, e.g. --out results"
        )
    longest = len(os.fsencode(target.name)) + len(".partial-") + 9  # the names made beside it
    limit = _name_max(target.parent)
    if longest > limit:
        raise CaromError(
            f"--out {target.name[:40]}... is {len(os.fsencode(target.name))} bytes long; the "
            f"file system allows {limit} per name and carom makes working names beside it "
            f"{longest - len(os.fsencode(target.name))} bytes longer: use a name of at most "
            f"{limit - (longest - len(os.fsencode(target.name)))} bytes"
        )
    if target.exists() and not target.is_dir():
        raise CaromError(f"{target} exists and is not a directory; choose another --out")
    if target.is_dir() and any(target.iterdir()) and not force:
        raise CaromError(
            f"{target} already exists and is not empty; choose another --out, or pass --force "
            f"to replace it"
        )
    return target


def _name_max(folder: Path) -> int:
    """The longest file name the file system holding ``folder`` takes [bytes] (255 where it
    does not say, or ``folder`` does not exist yet)."""
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    try:
        return int(os.pathconf(folder, "PC_NAME_MAX"))
    except (AttributeError, OSError, ValueError):
        return 255


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
    try:
        if target.exists():
            retired = Path(tempfile.mkdtemp(prefix=f".{target.name}.old-", dir=target.parent))
            target.rename(retired / target.name)
            staging.rename(target)
            shutil.rmtree(retired, ignore_errors=True)
        else:
            staging.rename(target)
    except OSError as exc:
        raise CaromError(
            f"cannot move the finished results from {staging} to {target}: {exc.strerror}; "
            f"they are complete in {staging}: move them by hand"
        ) from None
