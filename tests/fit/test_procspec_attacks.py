""".ProcSpec files as an untrusted client may upload them (bsdflab.service.fit_uploads reads
them in a check worker; ``bsdflab fit import`` and a fit's job read them too): every bad file
is refused with a ValueError naming the file, never another exception type (a traceback, or
the service's "could not be read (RuntimeError)"), never amplified past the reader's bound,
never read as the wrong numbers. Each test is bounded by construction, not by timing."""
from __future__ import annotations

import io
import zipfile

import pytest

from bsdflab.fit.readers import import_files
from bsdflab.service.fit_uploads import read_summary
from tests.fit.test_readers_instruments import PCT, SPEC, WL, procspec_chain_xml, write_procspec

WHERE = r"s\.ProcSpec: ps_0\.xml: "


def read(path):
    return import_files([str(path)], SPEC)


@pytest.mark.parametrize("ref", ["/", "//", "/.", "/./"])
def test_reference_to_no_element(tmp_path, ref):
    """An absolute reference of no steps names no element (it was an AttributeError)."""
    path = write_procspec(tmp_path / "s.ProcSpec", procspec_chain_xml(WL, PCT, ref))
    with pytest.raises(ValueError, match=WHERE + r"<processedPixels>: the reference '[/.]+' names no element"):
        read(path)


@pytest.mark.parametrize("ref", ["../../stage[2]", "../.."])
def test_reference_to_a_container(tmp_path, ref):
    """A reference to an element holding the array, not the array itself (XStream points at an
    earlier copy of the same double[]): refused, not read through its descendants."""
    path = write_procspec(tmp_path / "s.ProcSpec", procspec_chain_xml(WL, PCT, ref))
    with pytest.raises(ValueError, match=WHERE + r"<processedPixels> holds <(processedPixels|stage)>, "
                                                 r"not only <double> values"):
        read(path)


def test_nested_doubles_not_read(tmp_path):
    """Only the array's own <double> children: a <double> nested deeper is not one of its values."""
    xml = procspec_chain_xml(WL, PCT).replace("<stage><processedPixels><double>",
                                              "<stage><processedPixels><x><double>1.0</double></x><double>")
    path = write_procspec(tmp_path / "s.ProcSpec", xml)
    with pytest.raises(ValueError, match=WHERE + r"<processedPixels> holds <x>, not only <double> values"):
        read(path)


def dtd(entities: str) -> str:
    return f"<!DOCTYPE spectrum [{entities}]>\n" + procspec_chain_xml(WL, PCT)


@pytest.mark.parametrize("xml", [
    # entities (a 4.5 KB upload of them made 3.75 million elements, 31 s, +600 MB); expat's own
    # amplification guard lets a document grow 100-fold past 8 MiB, past the reader's 4 MiB bound
    dtd('<!ENTITY a "<x>1</x><x>1</x>"><!ENTITY b "&a;&a;">').replace("<certificates>", "<certificates>&b;"),
    dtd(""),
    '<?xml version="1.0"?>\n<!DOCTYPE spectrum SYSTEM "http://127.0.0.1:9/x.dtd">\n' + procspec_chain_xml(WL, PCT),
])
def test_dtd_refused(tmp_path, xml):
    path = write_procspec(tmp_path / "s.ProcSpec", xml)
    with pytest.raises(ValueError, match=WHERE + r"line \d+: a document type declaration \(<!DOCTYPE\)"):
        read(path)


def zip_bytes(compression=zipfile.ZIP_DEFLATED, name="ps_0.xml"):
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression) as z:
        z.writestr(name, procspec_chain_xml(WL, PCT))
    return bytearray(buf.getvalue())


def encrypted():
    b = zip_bytes()
    b[b.find(b"PK\x03\x04") + 6] |= 1    # general purpose flag bit 0: encrypted
    b[b.find(b"PK\x01\x02") + 8] |= 1
    return b


def method(m):
    b = zip_bytes()
    b[b.find(b"PK\x03\x04") + 8] = m     # compression method
    b[b.find(b"PK\x01\x02") + 10] = m
    return b


def corrupt_lzma():
    b = zip_bytes(zipfile.ZIP_LZMA)
    start = b.find(b"PK\x03\x04") + 30 + len("ps_0.xml")
    for k in range(start + 4, start + 40):
        b[k] ^= 0x55
    return b


def bad_utf8_name():
    b = zip_bytes(name="ps_0.xml\u00e9")   # the UTF-8 flag set, then a name that is not UTF-8
    return bytes(b).replace("ps_0.xml\u00e9".encode(), b"ps_0.xml\xff\xfe")


@pytest.mark.parametrize("make, match", [
    (encrypted, r"encrypted"),
    (lambda: method(9), r"compression method"),      # deflate64
    (lambda: method(99), r"compression method"),     # AES
    (corrupt_lzma, r""),
    (bad_utf8_name, r"utf-8"),
])
def test_unreadable_zip(tmp_path, make, match):
    """zipfile's RuntimeError, NotImplementedError, LZMAError and UnicodeDecodeError: a
    ValueError naming the file."""
    path = tmp_path / "s.ProcSpec"
    path.write_bytes(make())
    with pytest.raises(ValueError, match=r"s\.ProcSpec: not a readable ProcSpec \(zip\) archive: .*" + match):
        read(path)


def test_upload_zip_name_not_utf8(tmp_path):
    """The service's check of an upload: a zip, not 'not UTF-8 text'."""
    path = tmp_path / "upload"
    path.write_bytes(bad_utf8_name())
    with pytest.raises(ValueError, match=r"^s\.ProcSpec: not a readable zip archive \(UnicodeDecodeError\)"):
        read_summary(str(path), "s.ProcSpec", str(tmp_path))


@pytest.mark.parametrize("digits", ["1" * 5000, "0" * 5000 + "2", "1" * 10])
def test_reference_index_of_many_digits(tmp_path, digits):
    """An index of thousands of digits: int() refused it past 4300 digits with a ValueError
    naming neither the file nor the reference (and converts such strings in quadratic time
    where that limit is raised); no document has a billion siblings."""
    ref = f"../../stage[{digits}]/processedPixels"
    path = write_procspec(tmp_path / "s.ProcSpec", procspec_chain_xml(WL, PCT, ref))
    with pytest.raises(ValueError, match=WHERE + r"<processedPixels>: the reference '\.\./\.\./stage\[\d+\]/proc"
                                                 r"essedPixels' has a step XStream does not write"):
        read(path)


@pytest.mark.parametrize("ref, units", [
    ("../../stage[1]/processedPixels", ""),                                # the first stage's: raw counts
    ("../../../sourceSpectra/omni/pixelValues", ""),
    ("../../stage[2]/processedPixels", '<yUnits class="com.oceanoptics.spectrasuite.unitdescriptors.'
                                       'CountsIntensityDescriptor"/>'),
])
def test_last_stage_in_counts(tmp_path, ref, units):
    """A spectrum saved in scope mode: its last (only) stage's pixels are the raw counts (a
    reference to the source's <pixelValues>, or units in counts). Read as percent silently
    (40x the processed values here); refused by name."""
    xml = procspec_chain_xml(WL, PCT, ref).replace(f'reference="{ref}"/>', f'reference="{ref}"/>{units}')
    path = write_procspec(tmp_path / "s.ProcSpec", xml)
    with pytest.raises(ValueError, match=WHERE + r"the last <processedPixels> (is the <pixelValues> of <omni>|"
                                                 r"is in counts \(.*CountsIntensityDescriptor\)), .*scope mode"):
        read(path)


def test_tree_indexes_only_the_elements_stepped_into():
    """The children by tag are indexed for the elements a reference steps into, not for every
    element of the document (the eager index doubled the time a dense upload takes to read)."""
    from xml.etree import ElementTree

    from bsdflab.fit.readers.xstream import Tree

    junk = "<a><b/></a>" * 2000
    xml = procspec_chain_xml(WL, PCT).replace("<certificates>", f"<certificates><junk>{junk}</junk>")
    root = ElementTree.fromstring(xml)
    tree = Tree(root)
    el = root.findall(".//processedPixels")[-1]
    assert tree.resolve(el, "s").tag == "processedPixels"
    assert len(tree.named) == 2      # "../../stage[2]/processedPixels": certificates and stage[2]
