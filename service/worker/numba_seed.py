"""Seed numba's on-disk cache from one built with the image, before anything compiles.

Standard library only: importing the library (``service.app``, ``skelprune``) already
compiles a kernel or two into ``NUMBA_CACHE_DIR``, which must still be empty when the
seed is copied.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

__all__ = ["seed_numba_cache"]


def seed_numba_cache(seed: str | os.PathLike[str], target: str | os.PathLike[str]) -> int:
    """Copy a prebuilt numba cache into ``target`` unless ``target`` already has files.

    numba keys its cache on the source file's path and time stamp and on the CPU, so a
    cache built with the image is valid in its containers on a like CPU (else numba
    just compiles, as without a seed). The copy goes to a writable place, so a read-only
    root file system is fine. Returns the number of files copied (0: nothing to do).
    """
    src, dst = Path(seed), Path(target)
    if not src.is_dir() or (dst.is_dir() and any(dst.iterdir())):
        return 0
    shutil.copytree(src, dst, dirs_exist_ok=True)
    return sum(1 for p in dst.rglob("*") if p.is_file())
