"""Atomic file writing: a temporary file in the target folder, then a rename, so a reader
never sees a half-written file and an interrupted write leaves nothing behind."""
from __future__ import annotations

import os
import tempfile
from collections.abc import Callable


def _default_mode() -> int:
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def write_atomically(path: str | os.PathLike, write: Callable[[str], None], suffix: str = ".tmp") -> None:
    """Call ``write(tmp_path)`` to produce the file, then move it to ``path``.

    The file gets the permissions a plain ``open(path, "w")`` would (mkstemp's are 0600).
    """
    target = os.path.abspath(os.fspath(path))
    directory = os.path.dirname(target)
    os.makedirs(directory, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=directory, prefix=".", suffix=suffix)
    os.close(fd)
    try:
        write(tmp)
        os.chmod(tmp, _default_mode())
        os.replace(tmp, target)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
