"""Reading an untrusted ``.npz`` with bounded memory and time.

``numpy.load`` trusts an archive: a plain ``.npy`` under an ``.npz`` name comes back as one
array, an ``.npy`` header may claim any shape (numpy allocates it before reading a byte), and a
few megabytes of deflated zeros inflate to gigabytes. Here every limit is checked from the zip
directory and the ``.npy`` headers (numpy.lib.format reads them) before any array is read, so a
refused file costs a few kilobytes of reading, and an accepted one at most ``max_bytes``.
"""
from __future__ import annotations

import lzma
import math
import zipfile
import zlib
from pathlib import Path

import numpy as np
from numpy.lib import format as npy_format

NUMERIC_KINDS = "fiu"  # real floats, signed and unsigned integers
# What zipfile and numpy raise on a corrupt member (RuntimeError: encrypted or an unknown
# compression method; zlib/lzma errors: a corrupt stream; BadZipFile: a wrong CRC).
_READ_ERRORS = (ValueError, EOFError, OSError, RuntimeError, zlib.error, lzma.LZMAError,
                zipfile.BadZipFile)


class NpzError(ValueError):
    """An ``.npz`` file that is malformed or larger than its limits (the message says which)."""


def read_npz(path: str | Path, max_arrays: int, max_bytes: int) -> dict[str, np.ndarray]:
    """The real-numbered arrays of the ``.npz`` at ``path``, by name (without ``.npy``).

    NpzError, before any array is read, if the file is not a zip archive, holds more than
    ``max_arrays`` members, inflates to more than ``max_bytes`` in all, or a member is not an
    ``.npy`` of a real numeric dtype whose header's shape matches its size."""
    try:
        archive = zipfile.ZipFile(path)
    except zipfile.BadZipFile:
        with open(path, "rb") as file:
            plain = file.read(len(npy_format.MAGIC_PREFIX)) == npy_format.MAGIC_PREFIX
        raise NpzError("a plain .npy array, not an .npz archive of named arrays" if plain
                       else "not a zip archive (an .npz is one)") from None
    except _READ_ERRORS as exc:  # a damaged zip directory
        raise NpzError(f"not a readable zip archive ({first_line(exc)})") from None
    with archive:
        members = archive.infolist()
        if len(members) > max_arrays:
            raise NpzError(f"holds {len(members)} arrays (at most {max_arrays})")
        inflated = sum(member.file_size for member in members)  # [bytes], from the zip directory
        if inflated > max_bytes:
            raise NpzError(f"inflates to {inflated / 2**20:.0f} MB "
                           f"(at most {max_bytes / 2**20:.0f} MB)")
        for member in members:
            _check_header(archive, member)
        return {member.filename.removesuffix(".npy"): _read_array(archive, member)
                for member in members}


def _check_header(archive: zipfile.ZipFile, member: zipfile.ZipInfo) -> None:
    """The member is an ``.npy`` whose header's shape and dtype fill exactly its size."""
    name = member.filename
    if not name.endswith(".npy"):
        raise NpzError(f"member '{name}' is not an .npy array")
    try:
        with archive.open(member) as stream:
            version = npy_format.read_magic(stream)
            reader = {(1, 0): npy_format.read_array_header_1_0,
                      (2, 0): npy_format.read_array_header_2_0}.get(version)
            if reader is None:
                raise NpzError(f"'{name}' is an .npy of version {version} (1.0 or 2.0 are read)")
            shape, _, dtype = reader(stream)
            header_bytes = stream.tell()
    except NpzError:
        raise
    except _READ_ERRORS as exc:
        raise NpzError(f"'{name}' has no readable .npy header ({first_line(exc)})") from None
    if dtype.kind not in NUMERIC_KINDS:
        raise NpzError(f"'{name}' is not real numbers (dtype {dtype})")
    if any(size < 0 for size in shape):
        raise NpzError(f"'{name}' claims the shape {shape}")
    data_bytes = math.prod(shape) * dtype.itemsize  # exact: Python integers
    if header_bytes + data_bytes != member.file_size:
        raise NpzError(f"'{name}' claims the shape {shape} of {dtype} ({data_bytes} bytes) but "
                       f"holds {member.file_size - header_bytes} bytes of data")


def _read_array(archive: zipfile.ZipFile, member: zipfile.ZipInfo) -> np.ndarray:
    """The member's array (its header already checked against its size)."""
    try:
        with archive.open(member) as stream:
            return npy_format.read_array(stream, allow_pickle=False)
    except _READ_ERRORS as exc:
        raise NpzError(f"'{member.filename}' cannot be read ({first_line(exc)})") from None


def first_line(exc: BaseException) -> str:
    """An exception's message, one line, at most 200 characters (for a one-line error)."""
    text = str(exc).strip().splitlines()
    return text[0][:200] if text else type(exc).__name__
