"""Exceptions: every error of the engine is a :class:`ChiselError` carrying
the engine's message (file, position, what was expected)."""


class ChiselError(Exception):
    """Base class of every chisel error."""


class IoError(ChiselError, OSError):
    """A file could not be read or written."""


class FormatError(ChiselError, ValueError):
    """A file's content breaks its format (the message names the position)."""


class LimitError(ChiselError):
    """Input or output past a size limit or the memory budget."""


class ParameterError(ChiselError, ValueError):
    """An argument out of range, of the wrong shape or dtype, or unknown."""


class RefusedError(ChiselError):
    """A geometric operation refused its input (a non-orientable mesh, a
    knife touching a vertex, ...)."""


class GpuError(ChiselError):
    """No adapter, a lost device, GPU memory exhausted, a kernel failure."""


class DivergedError(ChiselError):
    """A relaxation diverged; ``report`` holds the engine's report (steps,
    increments, where it diverged)."""

    def __init__(self, message: str, report: dict):
        super().__init__(message)
        self.report = report


class CancelledError(ChiselError):
    """The operation was stopped by its caller."""


class InternalError(ChiselError):
    """A bug in chisel; please report it with the message."""


__all__ = [
    "ChiselError",
    "IoError",
    "FormatError",
    "LimitError",
    "ParameterError",
    "RefusedError",
    "GpuError",
    "CancelledError",
    "DivergedError",
    "InternalError",
]
