"""Content hashes (SHA-256, hex): the identity of input files and stored arrays."""

from __future__ import annotations

import hashlib
import os

import numpy as np


def file_sha256(path: str | os.PathLike) -> str:
    """SHA-256 of a file's bytes, read in 1 MiB blocks: the identity of an input file."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def array_sha256(array: np.ndarray) -> str:
    """SHA-256 of an array's bytes (C order): the content hash of an influence matrix."""
    return hashlib.sha256(np.ascontiguousarray(array).tobytes()).hexdigest()


def arrays_sha256(datasets: dict) -> str:
    """SHA-256 of named arrays (names sorted; dtype, shape and bytes of each)."""
    digest = hashlib.sha256()
    for name in sorted(datasets):
        array = np.ascontiguousarray(datasets[name])
        digest.update(f"{name}|{array.dtype.str}|{array.shape}|".encode())
        digest.update(array.tobytes())
    return digest.hexdigest()
