"""robodiff.Error: what robodiff raises when the C++ client reports a failed status."""


class Error(Exception):
    """A robodiff call failed.

    Attributes:
        code: the gRPC-style status name, e.g. ``"INVALID_ARGUMENT"``,
            ``"FAILED_PRECONDITION"``, ``"UNAVAILABLE"`` (docs/client.md lists them all).
        message: what went wrong and what to do about it.
    """

    def __init__(self, code: str, message: str) -> None:
        super().__init__(f"{code}: {message}")
        self.code = code
        self.message = message
