"""Atomic files (`bsdflab.util.files`): stale temporaries of dead writers are removed,
those of live writers and other programs' files are kept."""
from __future__ import annotations

import os
import subprocess
import sys
import time

from bsdflab.util.files import _HOST, stale_temporaries, write_atomically


def test_stale_temporaries_of_ours_are_removed(tmp_path):
    # old: a SIGKILLed write's ".xxxxxxxx.tmp.exr" stayed forever
    old = time.time() - 7200
    legacy = tmp_path / ".abcd1234.tmp.exr"
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    orphan = tmp_path / f".bsdflab-{_HOST}-{dead.pid}-x1y2z3.tmp.exr"
    fresh_legacy = tmp_path / ".wxyz9876.tmp.png"          # recent: maybe a writer at work
    live = tmp_path / f".bsdflab-{_HOST}-{os.getppid()}-q.tmp.exr"  # its process runs
    foreign = tmp_path / ".notes.tmp"                       # not our naming
    for p in (legacy, orphan, fresh_legacy, live, foreign):
        p.write_bytes(b"half")
    os.utime(legacy, (old, old))
    os.utime(foreign, (old, old))
    assert sorted(map(os.path.basename, stale_temporaries(str(tmp_path)))) == sorted([legacy.name, orphan.name])
    write_atomically(tmp_path / "x.txt", lambda tmp: open(tmp, "w").close())
    assert sorted(os.listdir(tmp_path)) == sorted([fresh_legacy.name, live.name, foreign.name, "x.txt"])
