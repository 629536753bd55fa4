"""robodiff.Client and robodiff.Model: connecting, loading robots, getting Functions.

Thin wrappers over the C++ client (robodiff._robodiff); the Function they return is the
compiled one, called without any Python in between.
"""

from __future__ import annotations

import json
import os
from typing import Any, Mapping, Optional, Union

from . import _robodiff
from ._robodiff import Function
from .jobs import JobsMixin

PathOrText = Union[str, "os.PathLike[str]"]


def _looks_like_text(value: PathOrText, marker: str) -> bool:
    return isinstance(value, str) and marker in value


class Model:
    """A robot loaded by a Client: sizes, names, and ``function(spec)``."""

    def __init__(self, client: "Client", info: "_robodiff.ModelInfo", urdf: Optional[PathOrText] = None,
                 floating_base: bool = False) -> None:
        self._client = client
        self._info = info
        self._urdf = urdf  # the URDF text or path it was loaded from (for the reference)
        self._floating_base = floating_base
        self._reference: Optional["_robodiff.ReferenceModel"] = None

    @property
    def id(self) -> str:
        """The model's canonical hash (the same for the same robot, wherever loaded)."""
        return self._info.id

    @property
    def nq(self) -> int:
        """Configuration size."""
        return self._info.nq

    @property
    def nv(self) -> int:
        """Velocity (tangent space) size."""
        return self._info.nv

    @property
    def joint_names(self) -> list[str]:
        """Joint names, in the model's order."""
        return list(self._info.joint_names)

    @property
    def frame_names(self) -> list[str]:
        """Frame names, in the model's order."""
        return list(self._info.frame_names)

    def function(self, spec: Union[Mapping[str, Any], PathOrText]) -> Function:
        """A compiled Function of this robot from a spec (docs/function-language.md).

        spec: a dict (written out with json.dumps), a JSON string (text starting with
        ``{``), or the path of a spec file (built-in and user functions alike). Waits until
        the function can be evaluated. Raises robodiff.Error (e.g. INVALID_ARGUMENT for a
        bad spec, FAILED_PRECONDITION in local mode when it is not in the cache).
        """
        native = self._client._native
        if isinstance(spec, Mapping):
            return native.function(self._info, json.dumps(spec))
        if isinstance(spec, str) and spec.lstrip().startswith("{"):
            return native.function(self._info, spec)
        if isinstance(spec, (str, os.PathLike)):
            return native.function_file(self._info, os.fspath(spec))
        raise TypeError(f"spec: {type(spec).__name__} given; a dict, a JSON string or a path is needed")

    def _reference_model(self) -> "_robodiff.ReferenceModel":
        """The robot parsed in this process (robodiff.reference, robodiff.check), parsed once."""
        if self._reference is None:
            if self._urdf is None:
                raise ValueError("this Model was not loaded by Client.load: no URDF to parse for the reference")
            text = self._urdf
            if not _looks_like_text(text, "<robot"):
                with open(os.fspath(text), "rb") as file:  # the bytes Client.load read
                    text = file.read().decode("utf-8")
            self._reference = _robodiff.ReferenceModel(text, self._floating_base, self.id)
        return self._reference

    def __repr__(self) -> str:
        return f"<robodiff.Model {self.id[:12]} nq={self.nq} nv={self.nv}>"


class Client(JobsMixin):
    """A connection to robodiff, mirroring the C++ ``robodiff::client::Client``.

    server: None reads ``$ROBODIFF_SERVER`` (unset: ``"auto"``); ``"auto"`` uses the cached
    library in this process when it can, else robodiffd over shared memory, else DDS;
    ``"local"`` insists on the cache (``robodiff warmup`` fills it; no server needed);
    ``"shm"``, ``"shm:<service>"``, ``"dds"``, ``"dds:<domain>"`` insist on a transport.
    cache_dir: the cache local mode reads (None: ``$ROBODIFF_CACHE_DIR``, else the
    default cache). timeout: seconds per call. Raises ValueError for a malformed server
    string, robodiff.Error (UNAVAILABLE) when an insisted mode cannot be reached.
    """

    def __init__(self, server: Optional[str] = None, *, cache_dir: Optional[PathOrText] = None,
                 timeout: float = 30.0) -> None:
        directory = None if cache_dir is None else os.fspath(cache_dir)
        self._native = _robodiff.Client(server, directory, float(timeout))

    @property
    def mode(self) -> str:
        """The mode in use: ``"local"``, ``"shm"`` or ``"dds"``."""
        return self._native.mode

    def load(self, urdf: PathOrText, floating_base: bool = False) -> Model:
        """Loads a robot from a URDF file's path or from URDF text (text contains ``<robot``).

        floating_base adds a free-flyer root joint (q = [x y z qx qy qz qw ...]). Raises
        robodiff.Error (INVALID_ARGUMENT naming the URDF's problem, UNAVAILABLE, ...).
        """
        if _looks_like_text(urdf, "<robot"):
            return Model(self, self._native.load_model(urdf, floating_base), urdf, floating_base)
        path = os.fspath(urdf)
        return Model(self, self._native.load_model_file(path, floating_base), os.path.abspath(path), floating_base)

    def __repr__(self) -> str:
        return f"<robodiff.Client mode={self.mode}>"
