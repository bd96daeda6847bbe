"""Output directories that are written completely or not at all."""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from carom.errors import CaromError

__all__ = ["check_output", "existing_folder", "publish", "staged_output", "write_whole"]


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
    length = len(os.fsencode(target.name))
    extra = len(".partial-") + 9  # the longest working name made beside it, less the name
    limit = _name_max(target.parent)
    if length + extra > limit:
        raise CaromError(
            f"--out {target.name[:40]}... is {length} bytes long; the file system allows "
            f"{limit} per name and carom makes working names beside it {extra} bytes longer: "
            f"use a name of at most {limit - extra} bytes"
        )
    if target.exists() and not target.is_dir():
        raise CaromError(f"{target} exists and is not a directory; choose another --out")
    if target.is_dir() and any(target.iterdir()) and not force:
        raise CaromError(
            f"{target} already exists and is not empty; choose another --out, or pass --force "
            f"to replace it"
        )
    return target


def existing_folder(path: Path) -> Path:
    """``path`` or its nearest ancestor that exists: where a folder yet to be made will live
    (for the file system's limits and free space)."""
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def _name_max(folder: Path) -> int:
    """The longest file name the file system holding ``folder`` takes [bytes] (255 where it
    does not say)."""
    try:
        return int(os.pathconf(existing_folder(folder), "PC_NAME_MAX"))
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


def write_whole(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file beside it, forced to disk, and a
    rename: ``path`` holds the old text or the new, never half of one."""
    temporary = path.with_name(f".{path.name}.tmp")
    with temporary.open("w", newline="", encoding="utf-8") as handle:
        handle.write(text)
        handle.flush()
        os.fsync(handle.fileno())
    temporary.replace(path)
