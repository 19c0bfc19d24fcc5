"""Split the SYNTHETIC ``examples/fit/stack_data.csv`` into two datasets of one sample, as two
sessions would measure it (not a measurement):

    python examples/fit/corefine/make_data.py

``session_a.csv`` holds its 15° and 30° rows, ``session_b.csv`` its 45° and 60° rows, each
with the source's comment lines (the truth) and header. ``corefine.toml`` fits them together.
"""

from __future__ import annotations

import os

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.join(HERE, "..", "stack_data.csv")
SESSIONS = {"session_a.csv": ("15.0", "30.0"), "session_b.csv": ("45.0", "60.0")}


def main() -> None:
    with open(SOURCE, encoding="utf-8") as f:
        lines = f.read().splitlines(keepends=True)
    head = [x for x in lines if x.startswith(("#", "angle_deg"))]
    rows = [x for x in lines if x not in head]
    for name, angles in SESSIONS.items():
        mine = [x for x in rows if x.split(",")[0] in angles]
        note = f"# session {name[8]}: the rows of examples/fit/stack_data.csv at {' and '.join(angles)} deg\n"
        with open(os.path.join(HERE, name), "w", encoding="utf-8") as f:
            f.write("".join(head[:-1] + [note] + head[-1:] + mine))


if __name__ == "__main__":
    main()
