"""What every reader returns, and the registry of readers by format name.

A reader turns one file into ``Spectrum`` objects: a wavelength axis and one measured curve,
with where each value came from (file, line, column) so that later checks can name it. The
long CSV reader is the exception: that file already is the fit's dataset (``read_dataset``).
Readers register as their classes are created (like ``bsdflab.bsdfs.base.TYPES``); every
format is a lazy entry, imported the first time its name is asked for.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from bsdflab.util.registry import Registry

READERS: Registry[Reader] = Registry("data format", lazy={
    "long": "bsdflab.fit.readers.long_csv",
    "wide": "bsdflab.fit.readers.wide_csv",
    "procspec": "bsdflab.fit.readers.oceanoptics_procspec",
    "oceanview": "bsdflab.fit.readers.oceanoptics_text",
    "avantes-ttt": "bsdflab.fit.readers.avantes_text",
    "avantes-raw8": "bsdflab.fit.readers.avantes_raw8",
    "jcamp": "bsdflab.fit.readers.jcamp_dx",
})


@dataclass
class Spectrum:
    """One measured curve as a file gives it.

    name: the column header (wide files) or "" (one curve per file; the file's name then
    carries the angle); lines: the 1-based line of each value (0 where the format has no
    lines, e.g. XML in a zip); units: what the file itself says ("percent", "fraction") or
    None; where: how messages name the curve ("data.csv: column 3 'R_15deg'").
    """

    wavelength_nm: np.ndarray
    value: np.ndarray
    file: str
    name: str
    where: str
    lines: np.ndarray
    units: str | None = None
    comments: tuple[str, ...] = ()    # the file's own comment lines (kept in the dataset)

    def at(self, i: int) -> str:
        """The message prefix for value ``i``."""
        line = int(self.lines[i]) if len(self.lines) else 0
        return f"{self.where}, line {line}" if line else f"{self.where}, value {i + 1}"


class Reader:
    """A file format. Subclasses set ``name``, ``suffixes``, ``description`` and ``read``."""

    name: ClassVar[str] = ""
    suffixes: ClassVar[tuple[str, ...]] = ()
    description: ClassVar[str] = ""
    long: ClassVar[bool] = False     # the file is the fit's long dataset (read_dataset)

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if cls.__dict__.get("name"):
            READERS.add(cls.name, cls())

    def claims(self, path: str, head: str) -> bool:
        """Whether a file with one of ``suffixes`` and these first characters is this format."""
        return True

    def read(self, path: str, spec) -> list[Spectrum]:
        # the long CSV (``long``) is read whole by read_dataset; it has no spectra to give
        raise ValueError(f"the {self.name} format gives a dataset, not spectra: import it as the fit's data")


def head_text(path: str, size: int = 4096) -> str:
    """The first ``size`` bytes of a file as text (undecodable bytes dropped), for ``claims``."""
    try:
        with open(path, "rb") as f:
            return f.read(size).decode("utf-8", errors="ignore")
    except OSError as e:
        raise ValueError(f"cannot read {path}: {e}") from None


def reader_for(path: str, name: str | None = None) -> Reader:
    """The reader called ``name``, or the one whose suffix and contents match ``path``."""
    if name is not None:
        reader = READERS.get(name)
        if reader is None:
            raise ValueError(f"unknown format {name!r}; known: {', '.join(READERS.names())}")
        return reader
    READERS.load_all()
    suffix = os.path.splitext(path)[1].lower()
    candidates = [r for _, r in sorted(READERS.items().items()) if suffix in r.suffixes]
    if not candidates:
        known = sorted({s for r in READERS.items().values() for s in r.suffixes})
        raise ValueError(f"{path}: cannot tell the format from the suffix {suffix or '(none)'!r} "
                         f"(known: {', '.join(known)}); name it with --format "
                         f"({', '.join(READERS.names())}) or format = \"...\" in the sidecar")
    head = head_text(path)
    for reader in sorted(candidates, key=lambda r: r.long, reverse=True):
        if reader.claims(path, head):
            return reader
    raise ValueError(f"{path}: not a file of the formats read from {suffix} files "
                     f"({', '.join(r.name for r in candidates)}); name the format with --format")
