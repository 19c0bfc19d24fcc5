"""Image files: linear HDR OpenEXR in and out, tone-mapped sRGB PNG out; writes are atomic."""
from __future__ import annotations

import os

import numpy as np

from bsdflab.spectra.srgb_curve import srgb_encode
from bsdflab.util.files import write_atomically, write_together
from bsdflab.util.native_output import quiet_native_output

EXR_SUFFIX, PNG_SUFFIX = ".tmp.exr", ".tmp.png"


def _rgb(image, name: str = "image") -> np.ndarray:
    a = np.asarray(image, dtype=np.float32)
    if a.ndim != 3 or a.shape[2] != 3 or a.shape[0] < 1 or a.shape[1] < 1:
        raise ValueError(f"{name} must have shape (H, W, 3), got {a.shape}")
    return a


def exr_writer(image, attributes: dict[str, str] | None = None):
    """A function writing linear RGB (H, W, 3) as a float32 OpenEXR to the path it is given
    (for ``bsdflab.util.files.write_together``)."""
    import OpenEXR

    a = _rgb(image)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    header.update({f"bsdflab.{k}": str(v) for k, v in (attributes or {}).items()})
    channels = {"RGB": np.ascontiguousarray(a)}
    return lambda tmp: OpenEXR.File(header, channels).write(tmp)


def write_exr(path: str | os.PathLike, image, attributes: dict[str, str] | None = None) -> None:
    """Linear RGB (H, W, 3) as a float32 OpenEXR; ``attributes`` go into the header as
    strings (render settings, timing)."""
    write_atomically(path, exr_writer(image, attributes), suffix=EXR_SUFFIX)


def png_writer(image, exposure: float = 0.0):
    """A function writing the tone-mapped sRGB PNG of ``image`` to the path it is given."""
    from PIL import Image

    pixels = tone_map(image, exposure)
    return lambda tmp: Image.fromarray(pixels, "RGB").save(tmp, format="PNG")


def write_exr_and_png(exr_path: str | os.PathLike, png_path: str | os.PathLike, image,
                      attributes: dict[str, str] | None = None, exposure: float = 0.0) -> None:
    """The EXR and its PNG, published together: an interrupt leaves both old files (or
    none) in place, never a new EXR without its PNG."""
    write_together([(exr_path, exr_writer(image, attributes), EXR_SUFFIX),
                    (png_path, png_writer(image, exposure), PNG_SUFFIX)])


def read_exr(path: str | os.PathLike) -> np.ndarray:
    """The RGB pixels (H, W, 3) float32 of an OpenEXR file, or a clear ValueError."""
    import OpenEXR

    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ValueError(f"image {path} does not exist")
    with open(path, "rb") as f:
        if f.read(4) != b"\x76\x2f\x31\x01":
            raise ValueError(f"{path} is not an OpenEXR file")
    with quiet_native_output() as noise:
        try:
            channels = OpenEXR.File(path, separate_channels=True).channels()
            pixels = {k: np.asarray(c.pixels, dtype=np.float32) for k, c in channels.items()}
        except Exception as e:  # the binding raises RuntimeError / ValueError / UnicodeError on damage
            failure = noise.first_line() or f"{type(e).__name__}: {e}"
        else:
            failure = None
    if failure is not None:
        raise ValueError(f"{path} is corrupt or unreadable: {failure}")
    names = {k.split(".")[-1].upper(): k for k in pixels}
    if not {"R", "G", "B"} <= set(names):
        if len(pixels) == 1:  # a grey image
            (only,) = pixels.values()
            return np.repeat(only[..., None], 3, axis=2)
        raise ValueError(f"{path} has no R, G, B channels (it has {', '.join(sorted(pixels))})")
    return np.stack([pixels[names[c]] for c in "RGB"], axis=2)


def tone_map(image, exposure: float = 0.0) -> np.ndarray:
    """Linear RGB -> 8-bit sRGB: scale by 2^exposure, clip to [0, 1], sRGB transfer curve
    (IEC 61966-2-1, as colour-science encodes it: ``srgb_encode``)."""
    a = np.clip(_rgb(image) * np.float32(2.0 ** exposure), 0.0, 1.0)
    encoded = srgb_encode(a)
    return np.round(np.nan_to_num(encoded) * 255).astype(np.uint8)


def write_png(path: str | os.PathLike, image, exposure: float = 0.0) -> None:
    """Tone-mapped sRGB PNG of a linear RGB image (see ``tone_map``)."""
    write_atomically(path, png_writer(image, exposure), suffix=PNG_SUFFIX)
