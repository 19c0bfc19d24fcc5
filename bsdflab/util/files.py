"""Atomic file writing: a temporary file in the target folder, then a rename, so a reader
never sees a half-written file and an interrupted write leaves nothing behind.

Temporaries are named ``.bsdflab-<host>-<pid>-<random><suffix>`` (e.g. ``.tmp.exr``). A process killed while
writing (SIGKILL, power loss) cannot remove its own, so the next write into the same folder
removes stale ones: those of a process on this host that no longer runs, and any older
than ``STALE_SECONDS``. Files of other naming are never touched, except the
``.<8 random characters>.tmp[.exr|.png]`` temporaries earlier bsdflab versions made,
once they are older than ``STALE_SECONDS``.

``write_together`` publishes a set of files (an EXR and its PNG) so that a reader finds
either the whole new set or none of it: every file is written to a temporary first, and
only then are all renamed, with SIGINT/SIGTERM held back for those few renames.
"""
from __future__ import annotations

import os
import re
import signal
import socket
import tempfile
import threading
import time
from collections.abc import Callable, Sequence

STALE_SECONDS = 3600.0
_HOST = re.sub(r"[^A-Za-z0-9_.]", "_", socket.gethostname())[:32] or "host"
_OURS = re.compile(r"^\.bsdflab-(?P<host>[A-Za-z0-9_.]+)-(?P<pid>[0-9]+)-[A-Za-z0-9_]+(\.[A-Za-z0-9]+)*$")
_LEGACY = re.compile(r"^\.[a-z0-9_]{8}\.tmp(\.exr|\.png)?$")
_cleaned: set[str] = set()
_cleaned_lock = threading.Lock()


def _default_mode() -> int:
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    return True


def stale_temporaries(directory: str, now: float | None = None) -> list[str]:
    """Paths of our stale temporaries in ``directory`` (see the module docstring)."""
    now = time.time() if now is None else now
    out = []
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return out
    for entry in entries:
        ours, legacy = _OURS.match(entry.name), _LEGACY.match(entry.name)
        if not (ours or legacy):
            continue
        try:
            if not entry.is_file(follow_symlinks=False):
                continue
            age = now - entry.stat(follow_symlinks=False).st_mtime
        except OSError:
            continue
        dead = bool(ours) and ours["host"] == _HOST and int(ours["pid"]) != os.getpid() \
            and not _alive(int(ours["pid"]))
        if dead or age > STALE_SECONDS:
            out.append(entry.path)
    return out


def remove_stale_temporaries(directory: str) -> int:
    """Remove our stale temporaries from ``directory``; returns how many were removed."""
    removed = 0
    for path in stale_temporaries(directory):
        try:
            os.unlink(path)
            removed += 1
        except OSError:
            pass  # another process got there first, or it is not ours to remove
    return removed


def _clean_once(directory: str) -> None:
    with _cleaned_lock:
        if directory in _cleaned:
            return
        _cleaned.add(directory)
    remove_stale_temporaries(directory)


def _temporary(target: str, suffix: str) -> str:
    directory = os.path.dirname(target)
    os.makedirs(directory, exist_ok=True)
    _clean_once(directory)
    fd, tmp = tempfile.mkstemp(dir=directory, prefix=f".bsdflab-{_HOST}-{os.getpid()}-", suffix=suffix)
    os.close(fd)
    return tmp


def write_atomically(path: str | os.PathLike, write: Callable[[str], None], suffix: str = ".tmp") -> None:
    """Call ``write(tmp_path)`` to produce the file, then move it to ``path``.

    The file gets the permissions a plain ``open(path, "w")`` would (mkstemp's are 0600).
    """
    write_together([(path, write, suffix)])


def write_together(items: Sequence[tuple[str | os.PathLike, Callable[[str], None], str]]) -> None:
    """Write several files so that they appear together: ``items`` are (path, write,
    suffix) as for ``write_atomically``. Every ``write`` runs first, into temporaries; if
    any fails (or Ctrl-C arrives) none of the targets changes. Then all are renamed in one
    go with SIGINT and SIGTERM deferred (on the main thread), so an interrupt cannot
    split the set."""
    targets = [os.path.abspath(os.fspath(path)) for path, _, _ in items]
    if len(set(targets)) != len(targets):
        raise ValueError(f"write_together needs distinct paths, got {targets}")
    temporaries: list[str] = []
    try:
        for (_, write, suffix), target in zip(items, targets):
            tmp = _temporary(target, suffix)
            temporaries.append(tmp)
            write(tmp)
            os.chmod(tmp, _default_mode())
        with _signals_deferred():
            for tmp, target in zip(temporaries, targets):
                os.replace(tmp, target)
            temporaries.clear()
    finally:
        for tmp in temporaries:
            if os.path.exists(tmp):
                os.unlink(tmp)


class _signals_deferred:
    """Hold SIGINT and SIGTERM until the block ends (main thread only; elsewhere a no-op)."""

    SIGNALS = {signal.SIGINT, signal.SIGTERM}

    def __enter__(self):
        self.active = (threading.current_thread() is threading.main_thread()
                       and hasattr(signal, "pthread_sigmask"))
        if self.active:
            self.previous = signal.pthread_sigmask(signal.SIG_BLOCK, self.SIGNALS)
        return self

    def __exit__(self, *exc):
        if self.active:
            signal.pthread_sigmask(signal.SIG_SETMASK, self.previous)
        return False
