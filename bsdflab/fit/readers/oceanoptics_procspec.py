"""Ocean Optics SpectraSuite .ProcSpec: a zip archive holding one XML document ``ps_<n>.xml``
(and ``OOISignatures.xml``).

The document (an XStream serialisation of SpectraSuite's ``ProcessedSpectrum``) holds the
wavelengths as ``<channelWavelengths><double>...</double>...</channelWavelengths>`` and the
processed spectrum (reflectance or transmittance, in percent as SpectraSuite shows it) as
``<processedPixels><double>...</double>...</processedPixels>``; beside them the raw sample,
dark and reference pixels (``pixelValues``, ``darkSpectrum``, ``referenceSpectrum``) and the
acquisition settings. A real file lists one ``processedPixels`` per stage of the processing
chain (in ``certificates``), most of them XStream references (``xstream.py``): the first
stage's points at the raw counts, so the last stage's is read, references followed (and
refused when it is those counts: a spectrum saved in scope mode).
SpectraSuite writes some bytes outside ASCII into the document; they are dropped before
parsing (as pavo/lightr do).
"""
from __future__ import annotations

import re
import zipfile
import zlib
from xml.etree import ElementTree

import numpy as np

from bsdflab.fit.readers.base import Reader, Spectrum
from bsdflab.fit.readers.xstream import Tree

try:
    from lzma import LZMAError
except ImportError:   # a Python without lzma: zipfile refuses such members with a RuntimeError
    LZMAError = zlib.error

_MEMBER = re.compile(r"(^|/)ps_\d+\.xml$")
_CONTROL = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f]")
# The archive is bounded here, in the reader, from its declared sizes (zipfile never inflates
# a member past its declared size): any file may reach this reader (a sidecar's format, a
# name with this suffix), so a check at upload alone let a zip bomb through.
MAX_MEMBERS = 64
# bytes the members may inflate to: a real document is under 1 MB; parsing 63 MiB of XML held
# the GIL 8.8 s and took +412 MB (a 160 KB upload), 4 MiB about half a second
MAX_INFLATED = 4 << 20


def _doubles(tree: Tree, tag: str, where: str, last: bool = False) -> np.ndarray:
    """The <double> values of the first (``last``: the last) <tag> element, references followed."""
    nodes = tree.root.findall(f".//{tag}")
    if not nodes:
        raise ValueError(f"{where}: no <{tag}> element")
    node = tree.resolve(nodes[-1 if last else 0], f"{where}: <{tag}>")
    # a double[] is its own <double> children only: a reference to an element holding one (a
    # stage, a spectrum) is not read through its descendants, which may be another array
    other = next((el for el in node if el.tag != "double"), None)
    if other is not None:
        raise ValueError(f"{where}: <{tag}> holds <{other.tag}>, not only <double> values")
    if last:
        _processed(tree, nodes[-1], node, tag, where)
    values = []
    for k, el in enumerate(node):
        try:
            values.append(float(el.text or ""))
        except ValueError:
            raise ValueError(f"{where}: <{tag}> value {k + 1} is not a number: {el.text!r}") from None
    if not values:
        raise ValueError(f"{where}: <{tag}> holds no <double> values")
    v = np.array(values)
    if not np.all(np.isfinite(v)):
        k = int(np.flatnonzero(~np.isfinite(v))[0])
        raise ValueError(f"{where}: <{tag}> value {k + 1} is not finite: {values[k]!r}")
    return v


def _processed(tree: Tree, el, node, tag: str, where: str) -> None:
    """ValueError when the last stage's ``el`` (resolved to ``node``) holds raw counts, not a
    processed spectrum: a spectrum saved in scope mode has one stage, whose pixels are a
    reference to the source spectrum's <pixelValues> (the first stage of any file is), and its
    units (<yUnits class="...CountsIntensityDescriptor">) say so. Read, they were taken as
    percent without a word."""
    if node.tag != tag:
        of = tree.up.get(node)
        raise ValueError(f"{where}: the last <{tag}> is the <{node.tag}>{f' of <{of.tag}>' if of is not None else ''}"
                         ", not a processed spectrum (raw counts saved in scope mode?)")
    stage = tree.up.get(el)
    units = stage.find("yUnits") if stage is not None else None
    if units is not None and "Counts" in (units.get("class") or ""):
        raise ValueError(f"{where}: the last <{tag}> is in counts ({units.get('class')}), not a processed "
                         "spectrum (saved in scope mode?)")


def check_sizes(infos: list[zipfile.ZipInfo], where: str) -> None:
    """ValueError when an archive has more than MAX_MEMBERS members or would inflate past
    MAX_INFLATED bytes."""
    if len(infos) > MAX_MEMBERS:
        raise ValueError(f"{where}: the archive has {len(infos)} members, more than {MAX_MEMBERS}")
    inflated = sum(i.file_size for i in infos)
    if inflated > MAX_INFLATED:
        raise ValueError(f"{where}: the archive inflates to {inflated} bytes, more than the limit of {MAX_INFLATED}")


class ProcSpec(Reader):
    name = "procspec"
    suffixes = (".procspec",)
    description = "Ocean Optics SpectraSuite .ProcSpec (a zip with an XML spectrum)"

    def read(self, path: str, spec) -> list[Spectrum]:
        try:
            with zipfile.ZipFile(path) as z:
                check_sizes(z.infolist(), path)
                members = [m for m in z.namelist() if _MEMBER.search(m)]
                if len(members) != 1:
                    raise ValueError(f"{path}: expected one ps_<n>.xml document in the archive, found "
                                     f"{members or 'none'} (members: {', '.join(z.namelist()) or 'none'})")
                member = members[0]
                raw = z.read(member)
        # zipfile's RuntimeError (an encrypted member), NotImplementedError (deflate64, AES),
        # LZMAError (a corrupt lzma member), UnicodeDecodeError (a name flagged UTF-8 that is not)
        except (zipfile.BadZipFile, zlib.error, EOFError, RuntimeError, NotImplementedError, LZMAError,
                UnicodeDecodeError) as e:
            raise ValueError(f"{path}: not a readable ProcSpec (zip) archive: {e}") from None
        except OSError as e:
            raise ValueError(f"cannot read {path}: {e}") from None
        where = f"{path}: {member}"
        text = _CONTROL.sub("", raw.decode("ascii", errors="ignore"))
        dtd = text.find("<!DOCTYPE")
        if dtd >= 0:   # SpectraSuite writes none; its entities inflate past MAX_INFLATED (expat's own
            # guard allows 100-fold past 8 MiB) and an external DTD is never wanted
            raise ValueError(f"{where}: line {text.count(chr(10), 0, dtd) + 1}: a document type declaration "
                             "(<!DOCTYPE), which SpectraSuite does not write, is not read")
        try:
            root = ElementTree.fromstring(text)
        except ElementTree.ParseError as e:
            line, column = e.position
            raise ValueError(f"{where}: line {line}, column {column + 1}: bad XML: {str(e).split(':')[0]}") from None
        tree = Tree(root)
        wl = _doubles(tree, "channelWavelengths", where)
        value = _doubles(tree, "processedPixels", where, last=True)
        if len(wl) != len(value):
            raise ValueError(f"{where}: {len(wl)} channelWavelengths but {len(value)} processedPixels")
        return [Spectrum(wl, value, path, "", f"{where} <processedPixels>", np.zeros(0, int))]
