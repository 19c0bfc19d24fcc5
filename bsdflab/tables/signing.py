"""Keyed signatures of table files: HMAC-SHA256 of the content hash under a secret key.

The content hash (``bsdflab.content_hash``) detects accidental damage but anyone can
recompute it after editing a file. A signature can only be made with the key, so a table
that verifies was written by a key holder and not changed since. The key comes from the
``key=`` argument of ``write_table`` / ``read_table`` or, by default, from the environment
variable ``BSDFLAB_TABLE_KEY`` (at least 16 characters; treat it like a password). With a
key configured, readers refuse unsigned files; without one, signatures are not checked.

signature = hex(HMAC-SHA256(key, b"bsdflab-table-signature-v1:" + content_hash_hex_ascii))
"""
from __future__ import annotations

import hashlib
import hmac

from bsdflab.util.settings import library_settings

ENV_VAR = "BSDFLAB_TABLE_KEY"
MIN_KEY_BYTES = 16
_CONTEXT = b"bsdflab-table-signature-v1:"


def resolve_key(key: bytes | str | None) -> bytes | None:
    """The key to use: ``key`` when given, else ``$BSDFLAB_TABLE_KEY``, else None."""
    if key is None:
        secret = library_settings().table_key   # BSDFLAB_TABLE_KEY
        if secret is None:
            return None
        key = secret.get_secret_value()
    if isinstance(key, str):
        key = key.encode("utf-8")
    if not isinstance(key, (bytes, bytearray)):
        raise ValueError(f"a table signing key must be bytes or a string, got {type(key).__name__}")
    if len(key) < MIN_KEY_BYTES:
        raise ValueError(f"a table signing key must have at least {MIN_KEY_BYTES} bytes "
                         f"(check {ENV_VAR}), got {len(key)}")
    return bytes(key)


def sign(key: bytes, content_hash: str) -> str:
    """The signature (64 hex digits) of a file with this content hash."""
    return hmac.new(key, _CONTEXT + content_hash.encode("ascii"), hashlib.sha256).hexdigest()


def verify(key: bytes, content_hash: str, signature: str) -> bool:
    """True when ``signature`` is this key's signature of ``content_hash`` (constant time)."""
    if not isinstance(signature, str):
        return False
    return hmac.compare_digest(sign(key, content_hash), signature.strip().lower())
