"""robodiff.cache: what the cache of compiled functions holds, as ``robodiff cache ls`` shows it.

    import robodiff
    for entry in robodiff.cache.ls():          # most recently used first
        print(entry.key[:12], entry.robot, entry.function, entry.total_bytes)
"""

from __future__ import annotations

import datetime
import json
import os
import pathlib
from dataclasses import dataclass
from typing import Any, List, Optional, Union

from . import _robodiff

PathLike = Union[str, "os.PathLike[str]"]


@dataclass(frozen=True)
class CacheEntry:
    """One entry of the cache: the fields of ``robodiff cache ls --json``.

    key: the cache key (SHA-256 hex); robot, function: the model's and the function's
    names; state: ``"ready"`` or ``"building"``; model_hash: the model's canonical hash
    (``Model.id``); spec: the function spec (a dict); sizes: the function's block sizes;
    library_bytes / total_bytes: the library's and the whole entry's size on disk;
    created / last_used: unix seconds (last_used 0: never loaded); hits: loads; owner,
    lease_expires_ms: who builds it while ``building``.
    """

    key: str
    robot: str
    function: str
    state: str
    model_hash: str
    spec: Any
    sizes: Any
    compiler: str
    build_seconds: float
    library_bytes: int
    total_bytes: int
    library_sha256: str
    created: int
    last_used: int
    hits: int
    owner: str
    lease_expires_ms: int

    @property
    def created_at(self) -> datetime.datetime:
        """``created`` as an aware UTC datetime."""
        return datetime.datetime.fromtimestamp(self.created, datetime.timezone.utc)

    @property
    def last_used_at(self) -> Optional[datetime.datetime]:
        """``last_used`` as an aware UTC datetime; None when never loaded."""
        return datetime.datetime.fromtimestamp(self.last_used, datetime.timezone.utc) if self.last_used > 0 else None


def default_dir() -> pathlib.Path:
    """The cache used when none is given: $ROBODIFF_CACHE_DIR, else $XDG_CACHE_HOME/robodiff, else ~/.cache/robodiff."""
    return pathlib.Path(_robodiff.default_cache_dir())


def ls(cache_dir: Optional[PathLike] = None) -> List[CacheEntry]:
    """The cache's entries, most recently used first; [] when the directory does not exist.

    cache_dir: None is the default cache (default_dir()). Raises robodiff.Error
    (FAILED_PRECONDITION naming the directory) for a directory that cannot be used.
    """
    directory = None if cache_dir is None else os.fspath(cache_dir)
    return [CacheEntry(**row) for row in json.loads(_robodiff.cache_entries(directory))]


__all__ = ["CacheEntry", "default_dir", "ls"]
