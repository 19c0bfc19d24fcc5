"""Table files: a `TableData` as one single-part, scanline OpenEXR image (docs/table_format.md).

Layout
------
Each 6-D array ``values[lobe, thickness, theta_i, theta_o, phi, channel]`` becomes one 2-D
float32 image per channel, of height ``n_lobe * n_thickness * n_theta_i`` and width
``n_theta_o * n_phi``::

    row    = (lobe * n_thickness + thickness) * n_theta_i + theta_i
    column = theta_o * n_phi + phi

i.e. ``image = values[..., c].reshape(n_lobe * n_thickness * n_theta_i, n_theta_o * n_phi)``
(numpy C order). Each row is one incidence (lobe, film thickness, theta_i); along it,
theta_o is the slow index and phi the fast one. Channels are

* ``f.<name>``   FLOAT: ``values[..., c]``, the BSDF value f (no cosine) in 1/sr
* ``err.<name>`` FLOAT: ``stderr[..., c]``, its standard error
* ``samples``    UINT:  ``samples``, the random walks spent on each cell

where ``<name>`` is ``R``, ``G``, ``B`` or a wavelength in nm as written in
``bsdflab.channels`` (e.g. ``f.412.5``). Compression is ZIP (lossless).

Metadata
--------
String header attributes, JSON where structured: ``bsdflab.format_version``,
``bsdflab.version``, ``bsdflab.model``, ``bsdflab.grid``, ``bsdflab.lobes``,
``bsdflab.channels``, ``bsdflab.colour_space``, ``bsdflab.units``, ``bsdflab.layout``,
``bsdflab.split_direct``, ``bsdflab.rel_error_target``, ``bsdflab.meta`` and
``bsdflab.content_hash``; optionally ``bsdflab.signature`` (format version 2).

Content hash
------------
``bsdflab.content_hash`` is the lowercase hex SHA-256 of, in this order:

1. the canonical JSON of every other ``bsdflab.*`` attribute (``bsdflab.signature``
   excepted) as an object mapping the
   attribute name to its string value (keys sorted, separators ``","`` and ``":"``, ASCII
   only -- Python's ``json.dumps(d, sort_keys=True, separators=(",", ":"))``), as UTF-8;
2. the raw bytes of every channel image, row-major, little-endian: ``f.<name>`` for each
   channel in ``bsdflab.channels`` order, then ``err.<name>`` in the same order, then
   ``samples`` (uint32).

So any accidental change to the pixels or to the bsdflab metadata is detected. The hash
is unkeyed: anyone can recompute it after an edit. ``bsdflab.signature`` (written when a
key is configured, see ``bsdflab.tables.signing``) is an HMAC-SHA256 of the content hash
under a secret key: only key holders can make a file that verifies. On load every field
is also re-validated for meaning (``TableData.check``, the model through ``from_dict``).
"""
from __future__ import annotations

import hashlib
import json
import os
from typing import Any

import numpy as np

from bsdflab._version import __version__
from bsdflab.tables import signing
from bsdflab.tables.data import FORMAT_VERSION, TableData, TableGrid
from bsdflab.util import limits
from bsdflab.util.files import write_atomically
from bsdflab.util.native_output import quiet_native_output

PREFIX = "bsdflab."
HASH_ATTRIBUTE = PREFIX + "content_hash"
SIGNATURE_ATTRIBUTE = PREFIX + "signature"
UNHASHED = (HASH_ATTRIBUTE, SIGNATURE_ATTRIBUTE)
REQUIRED = tuple(PREFIX + name for name in (
    "format_version", "version", "model", "grid", "lobes", "channels", "colour_space", "units",
    "layout", "split_direct", "rel_error_target", "meta", "content_hash"))
# 1 differs from 2 only in having no signature; 1 and 2 hold a transmissive model's light
# from above only (lobes reflection, transmission), 3 from both sides (four lobes).
SUPPORTED_VERSIONS = (1, 2, FORMAT_VERSION)

RGB_COLOUR_SPACE = "linear sRGB (D65)"
SPECTRAL_COLOUR_SPACE = "spectral, nm"
UNITS = {"angles": "rad", "f": "1/sr (BSDF value without the cosine)", "thickness": "nm",
         "wavelength": "nm"}
LAYOUT = {"rows": ["lobe", "thickness", "theta_i"], "columns": ["theta_o", "phi"],
          "order": "row-major, last index fastest"}
SAMPLES_CHANNEL = "samples"


def value_channel(name: str) -> str:
    return f"f.{name}"


def error_channel(name: str) -> str:
    return f"err.{name}"


def canonical_json(value: Any) -> str:
    """Deterministic JSON (sorted keys, no spaces, ASCII); numpy values become plain ones."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=True,
                      allow_nan=False, default=_plain)


def _plain(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON-serialisable")


def to_images(array: np.ndarray) -> np.ndarray:
    """(n_lobe, n_t, n_ti, n_to, n_phi[, C]) -> (n_lobe * n_t * n_ti, n_to * n_phi[, C])."""
    l, t, ti, to, p = array.shape[:5]
    return array.reshape(l * t * ti, to * p, *array.shape[5:])


def content_hash(attributes: dict[str, str], images: list[np.ndarray]) -> str:
    """SHA-256 over the bsdflab attributes (all but the hash) and the channel images."""
    h = hashlib.sha256()
    others = {k: v for k, v in attributes.items() if k.startswith(PREFIX) and k not in UNHASHED}
    h.update(canonical_json(others).encode("utf-8"))
    for image in images:
        little = image.astype(image.dtype.newbyteorder("<"), copy=False)
        h.update(np.ascontiguousarray(little).tobytes())
    return h.hexdigest()


def _attributes(table: TableData) -> dict[str, str]:
    def encoded(name: str, value: Any) -> str:
        try:
            return canonical_json(value)
        except (TypeError, ValueError) as e:
            raise ValueError(f"table {name} cannot be stored as JSON: {e}") from None

    return {
        PREFIX + "format_version": str(FORMAT_VERSION),
        PREFIX + "version": __version__,
        PREFIX + "model": encoded("model", table.model),
        PREFIX + "grid": encoded("grid", table.grid.to_dict()),
        PREFIX + "lobes": encoded("lobes", list(table.lobes)),
        PREFIX + "channels": encoded("channels", list(table.channels)),
        PREFIX + "colour_space": SPECTRAL_COLOUR_SPACE if table.spectral else RGB_COLOUR_SPACE,
        PREFIX + "units": canonical_json(UNITS),
        PREFIX + "layout": canonical_json(LAYOUT),
        PREFIX + "split_direct": canonical_json(bool(table.split_direct)),
        PREFIX + "rel_error_target": encoded("rel_error_target", float(table.rel_error_target)),
        PREFIX + "meta": encoded("meta", table.meta),
    }


def _channel_images(table: TableData) -> dict[str, np.ndarray]:
    """Channel name -> 2-D image, in hash order."""
    values = to_images(np.asarray(table.values, dtype=np.float32))
    errors = to_images(np.asarray(table.stderr, dtype=np.float32))
    images = {value_channel(n): np.ascontiguousarray(values[..., c])
              for c, n in enumerate(table.channels)}
    images.update({error_channel(n): np.ascontiguousarray(errors[..., c])
                   for c, n in enumerate(table.channels)})
    images[SAMPLES_CHANNEL] = np.ascontiguousarray(to_images(table.samples).astype(np.uint32))
    return images


def write_table(path: str | os.PathLike, table: TableData, key: bytes | str | None = None) -> None:
    """Write `table` to `path` as an OpenEXR table file, atomically.

    Parameters
    ----------
    path : str or path-like
        Target file (conventionally ``.exr``); its folder is created if missing.
    table : TableData
        Must pass ``table.check()``; values and stderr are stored as float32, samples as
        uint32 (so they must be >= 0).
    key : bytes or str, optional
        Signing key (``bsdflab.tables.signing``); default ``$BSDFLAB_TABLE_KEY``. With a
        key the file carries ``bsdflab.signature``.

    Raises
    ------
    ValueError
        If the table is inconsistent or its model / meta cannot be stored as JSON.
    """
    import OpenEXR

    table.check()
    names = [str(n) for n in table.channels]
    if any(not n for n in names) or len(set(names)) != len(names):
        raise ValueError(f"table channel names must be distinct and non-empty, got {names}")
    if table.samples.size and int(np.min(table.samples)) < 0:
        raise ValueError("table samples must be >= 0")
    attributes = _attributes(table)
    images = _channel_images(table)
    attributes[HASH_ATTRIBUTE] = content_hash(attributes, list(images.values()))
    secret = signing.resolve_key(key)
    if secret is not None:
        attributes[SIGNATURE_ATTRIBUTE] = signing.sign(secret, attributes[HASH_ATTRIBUTE])
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage, **attributes}

    def write(tmp: str) -> None:
        # OpenEXR.File turns the dict's arrays into Channel objects: give it a copy.
        OpenEXR.File(header, dict(images)).write(tmp)

    write_atomically(path, write, suffix=".tmp.exr")


def read_attributes(path: str | os.PathLike) -> dict[str, str]:
    """The ``bsdflab.*`` header attributes of a table file, unverified (header only).

    Raises
    ------
    ValueError
        If the file is missing or not an OpenEXR file.
    """
    header, _ = _open(os.fspath(path), header_only=True)
    return {k: v for k, v in header.items() if k.startswith(PREFIX)}


def read_table(path: str | os.PathLike, key: bytes | str | None = None) -> TableData:
    """Read a table file and verify it: format version, shapes, content hash, signature
    (when a key is configured) and the meaning of every field.

    Parameters
    ----------
    path : str or path-like
    key : bytes or str, optional
        Verification key; default ``$BSDFLAB_TABLE_KEY``. With a key, unsigned files and
        files whose signature does not verify are refused.

    Raises
    ------
    ValueError
        Naming the problem: missing file, not an EXR file, not a bsdflab table, written by
        an unsupported format version, corrupt (unreadable, inconsistent, or changed
        after it was written), invalid (a field out of range, a model ``from_dict``
        refuses), unsigned or wrongly signed when a key is set, or too large for the
        memory cap (``bsdflab.util.limits``).
    """
    path = os.fspath(path)
    if not isinstance(path, str):
        raise ValueError("a table path must be a string")
    header, _ = _open(path, header_only=True)
    _check_version(path, header)
    _check_size(path, header)
    header, channels = _open(path, header_only=False)

    def corrupt(why: str) -> ValueError:
        return ValueError(f"table file {path} is corrupt: {why}")

    missing = [name for name in REQUIRED if name not in header]
    if missing:
        raise ValueError(f"{path} is not a bsdflab table (missing attribute {', '.join(missing)})")
    attributes = {k: v for k, v in header.items() if k.startswith(PREFIX)}
    if any(not isinstance(v, str) for v in attributes.values()):
        raise corrupt("a bsdflab.* attribute is not a string")

    def parsed(name: str) -> Any:
        try:
            return json.loads(attributes[PREFIX + name], parse_constant=_no_constant)
        except json.JSONDecodeError as e:
            raise corrupt(f"attribute {PREFIX + name} is not valid JSON ({e})") from None
        except ValueError as e:  # NaN / Infinity, which canonical JSON never writes
            raise corrupt(f"attribute {PREFIX + name}: {e}") from None
        except RecursionError:
            raise corrupt(f"attribute {PREFIX + name} is nested too deeply") from None

    names = parsed("channels")
    if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
        raise corrupt(f"attribute {PREFIX}channels must be a non-empty list of names")
    wanted = ([(value_channel(n), np.float32) for n in names]
              + [(error_channel(n), np.float32) for n in names] + [(SAMPLES_CHANNEL, np.uint32)])
    images = []
    for name, dtype in wanted:
        if name not in channels:
            raise corrupt(f"channel {name} is missing")
        pixels = channels[name]
        if pixels.dtype != dtype:
            raise corrupt(f"channel {name} holds {pixels.dtype}, expected {np.dtype(dtype)}")
        images.append(pixels)
    if content_hash(attributes, images) != attributes[HASH_ATTRIBUTE]:
        raise corrupt("content hash mismatch (file changed after it was written)")
    _check_signature(path, attributes, key)
    table = _table_from(parsed, attributes, images, len(names), corrupt)
    try:
        table.check_model()
    except ValueError as e:
        raise ValueError(f"table file {path} is invalid: its model: {e}") from None
    return table


def _check_signature(path: str, attributes: dict[str, str], key) -> None:
    secret = signing.resolve_key(key)
    if secret is None:
        return  # nothing to verify against; the content hash still caught accidents
    signature = attributes.get(SIGNATURE_ATTRIBUTE)
    if signature is None:
        raise ValueError(f"table file {path} is not signed, and a signing key is set "
                         f"({signing.ENV_VAR}): refusing an unsigned table")
    if not signing.verify(secret, attributes[HASH_ATTRIBUTE], signature):
        raise ValueError(f"table file {path} has a signature that does not verify with the "
                         "configured key (signed with another key, or edited and re-hashed)")


def _check_size(path: str, header: dict[str, Any]) -> None:
    """Refuse a table whose declared grid exceeds the caps, before reading any pixels."""
    try:
        grid = TableGrid.from_dict(json.loads(header[PREFIX + "grid"]))
        n_lobes = len(json.loads(header[PREFIX + "lobes"]))
        n_channels = len(json.loads(header[PREFIX + "channels"]))
    except (KeyError, TypeError, ValueError, RecursionError):
        return  # malformed headers are reported by the full checks that follow
    limits.check_bytes(f"table file {path} ({grid.cells(n_lobes)} cells x {n_channels} channels)",
                       limits.table_bytes(grid.cells(n_lobes), n_channels))


def _no_constant(name: str):
    raise ValueError(f"{name} is not allowed")


def _table_from(parsed, attributes, images, n_channels, corrupt) -> TableData:
    """Rebuild the TableData from verified attributes and channel images."""
    try:
        grid = TableGrid.from_dict(parsed("grid"))
        lobes = tuple(parsed("lobes"))
        channels = tuple(parsed("channels"))
        model, meta = parsed("model"), parsed("meta")
        split_direct, rel_error = parsed("split_direct"), parsed("rel_error_target")
        if not isinstance(model, dict) or not isinstance(meta, dict):
            raise ValueError("model and meta must be JSON objects")
        if not isinstance(split_direct, bool) or not isinstance(rel_error, (int, float)):
            raise ValueError("split_direct must be a boolean and rel_error_target a number")
        if parsed("layout") != LAYOUT:
            raise ValueError(f"unknown pixel layout {attributes[PREFIX + 'layout']}")
        n_lobe, n_t = len(lobes), max(1, len(grid.thickness_nm))
        cells = (n_lobe, n_t, grid.n_theta_i, grid.n_theta_o, grid.n_phi)
        expected = (n_lobe * n_t * grid.n_theta_i, grid.n_theta_o * grid.n_phi)
        if any(image.shape != expected for image in images):
            raise ValueError(f"channel images are {images[0].shape}, the grid needs {expected}")
        values = np.stack(images[:n_channels], axis=-1).reshape(*cells, n_channels)
        stderr = np.stack(images[n_channels:2 * n_channels], axis=-1).reshape(*cells, n_channels)
        samples = images[-1].reshape(cells)
        if samples.size and int(samples.max()) > np.iinfo(np.int32).max:
            raise ValueError("samples exceed the int32 range")
        table = TableData(model=model, grid=grid, lobes=lobes, channels=channels,
                          split_direct=split_direct, values=values, stderr=stderr,
                          samples=samples.astype(np.int32), rel_error_target=float(rel_error),
                          meta=meta)
        table.check()
    except (ValueError, KeyError, TypeError) as e:
        raise corrupt(str(e)) from None
    return table


def _check_version(path: str, header: dict[str, Any]) -> None:
    name = PREFIX + "format_version"
    if name not in header:
        raise ValueError(f"{path} is not a bsdflab table (missing attribute {name})")
    try:
        version = int(header[name])
    except (TypeError, ValueError):
        raise ValueError(f"table file {path} is corrupt: bad {name} {header[name]!r}") from None
    if version not in SUPPORTED_VERSIONS:
        readable = ", ".join(str(v) for v in SUPPORTED_VERSIONS)
        raise ValueError(f"table file {path} was written by format version {version}, "
                         f"this bsdflab reads versions {readable}")


def _open(path: str, header_only: bool) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """(header, channel name -> pixels) of a single-part EXR file, or a clear ValueError."""
    import OpenEXR

    if os.path.isdir(path):
        raise ValueError(f"{path} is a folder, not a table file")
    if not os.path.isfile(path):
        raise ValueError(f"table file {path} does not exist")
    try:
        with open(path, "rb") as f:
            magic = f.read(4)
    except OSError as e:
        raise ValueError(f"cannot read table file {path}: {e.strerror}") from None
    if magic != b"\x76\x2f\x31\x01":
        raise ValueError(f"{path} is not a bsdflab table (not an OpenEXR file)")
    # The library reports damage by printing (stdout and C stderr) and leaving an empty
    # file object; capture the noise and turn it into one message.
    with quiet_native_output() as noise:
        try:
            exr = OpenEXR.File(path, separate_channels=True, header_only=header_only)
            header = dict(exr.header())
            channels = {} if header_only else {k: c.pixels for k, c in exr.channels().items()}
        except Exception as e:  # the binding raises RuntimeError / ValueError on damage
            failure = str(e)
        else:
            failure = None
    if failure is not None:
        detail = noise.first_line() or failure
        raise ValueError(f"table file {path} is corrupt or not a table: unreadable EXR ({detail})")
    return header, channels
