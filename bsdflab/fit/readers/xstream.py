"""XStream XML references, as SpectraSuite writes them in a .ProcSpec document.

XStream (the Java serialiser behind OmniDriver) writes an object it has already written as
an empty element whose ``reference`` attribute is an XPath to the first copy, relative to
the element itself (``../../../sourceSpectra/com.oceanoptics.omnidriver.spectra.OmniSpectrum/
pixelValues``; ``name[2]`` is the second sibling of that name) or absolute (``/root/...``).
A real file's processed spectrum is mostly such references: reading an element without
following them finds no values, or the raw counts another element points at.
"""
from __future__ import annotations

import re
from xml.etree import ElementTree

# an index of at most 9 digits: no document has a billion siblings, and int() of thousands of
# digits raises its own ValueError (quadratic where its limit is lifted)
_STEP = re.compile(r"^([^\[\]/]+)(?:\[(\d{1,9})\])?$")
MAX_HOPS = 16    # a reference to a reference ...: more than this is a cycle
# steps in one reference: real ones have under ten; any document may reach the reader (an
# upload), so a path is bounded, and each step is a dictionary look-up, not a scan
MAX_STEPS = 64


class Tree:
    """A parsed document with each element's parent (ElementTree keeps none), built in one
    pass, and the children by tag of the elements a reference steps into, indexed when first
    stepped into (each element's children once: at most one more pass, not one per document
    element; on a dense 4 MiB upload the eager index took twice the parents' time)."""

    def __init__(self, root: ElementTree.Element):
        self.root = root
        self.up: dict[ElementTree.Element, ElementTree.Element] = {c: p for p in root.iter() for c in p}
        self.named: dict[ElementTree.Element, dict[str, list[ElementTree.Element]]] = {}

    def children(self, node: ElementTree.Element, name: str) -> list[ElementTree.Element]:
        """``node``'s children called ``name``, in document order."""
        by_tag = self.named.get(node)
        if by_tag is None:
            by_tag = self.named[node] = {}
            for child in node:
                by_tag.setdefault(child.tag, []).append(child)
        return by_tag.get(name, [])

    def _follow(self, el, path: str, where: str):
        steps = [s for s in path.split("/") if s not in ("", ".")]
        if len(steps) > MAX_STEPS:
            raise ValueError(f"{where}: a reference of {len(steps)} steps (at most {MAX_STEPS})")
        node = None if path.startswith("/") else el
        for step in steps:
            if step == "..":
                node = self.up.get(node) if node is not None else None
                if node is None:
                    raise ValueError(f"{where}: the reference {path!r} climbs above the document")
                continue
            m = _STEP.match(step)
            if m is None:
                raise ValueError(f"{where}: the reference {path!r} has a step XStream does not write: {step!r}")
            name, k = m.group(1), int(m.group(2) or 1)
            same = ([self.root] if self.root.tag == name else []) if node is None else self.children(node, name)
            if not 1 <= k <= len(same):
                raise ValueError(f"{where}: the reference {path!r} names no element at {step!r}")
            node = same[k - 1]
        if node is None:   # "/": an absolute path of no steps names the document, not an element
            raise ValueError(f"{where}: the reference {path!r} names no element")
        return node

    def resolve(self, el: ElementTree.Element, where: str) -> ElementTree.Element:
        """The element ``el`` stands for: itself, or what its ``reference`` chain points at."""
        for _ in range(MAX_HOPS):
            path = el.get("reference")
            if path is None:
                return el
            el = self._follow(el, path, where)
        raise ValueError(f"{where}: more than {MAX_HOPS} references in a chain (a cycle)")
