"""Reading text exports: lines with their numbers, cells, numbers with file/line/column errors."""
from __future__ import annotations

import math


def read_lines(path: str) -> list[str]:
    """The file's lines (UTF-8, a byte-order mark dropped; Latin-1 if it is not UTF-8, as
    instrument software on Windows writes)."""
    try:
        with open(path, "rb") as f:
            raw = f.read()
    except OSError as e:
        raise ValueError(f"cannot read {path}: {e}") from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    return text.replace("\x00", "").splitlines()


def number(text: str, where: str, what: str, decimal: str = ".") -> float:
    """``text`` as a finite float; ValueError naming ``where`` (file, line, column) otherwise."""
    cell = text.strip()
    if decimal != ".":
        cell = cell.replace(decimal, ".")
    try:
        value = float(cell)
    except ValueError:
        hint = " (a decimal comma? set decimal = \",\" in the sidecar)" if "," in cell and decimal == "." else ""
        raise ValueError(f"{where}: {what} must be a number, got {text.strip()!r}{hint}") from None
    if not math.isfinite(value):
        raise ValueError(f"{where}: {what} must be finite, got {text.strip()!r}")
    return value


def split(line: str, delimiter: str | None) -> list[str]:
    """Cells of a line; ``delimiter`` None splits on runs of whitespace."""
    return line.split() if delimiter is None else [c.strip() for c in line.split(delimiter)]
