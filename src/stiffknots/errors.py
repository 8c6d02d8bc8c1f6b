"""One family of errors: every error stiffknots raises on purpose derives from
:class:`StiffKnotsError`.

Two branches matter to a caller:

* :class:`UserInputError` (also a ``ValueError``) — a mistake of the user: an unknown knot, an
  impossible parameter, a chain that does not fit, an unreadable file, a checkpoint of another
  run. The message says what was wrong and what is allowed. The command line prints it as one
  line and exits with code 2, before any work is done where it can be checked before.
* :class:`VerificationError` (also a ``RuntimeError``) — a result that failed its verification
  (knot type changed, energy bookkeeping drifted, bonds or exclusion broken). The moves and the
  minimiser preserve all of these by construction, so such an error is a bug of stiffknots and
  never a data point.

:class:`RunStopped` is not an error of either kind: a run that stopped on request after writing
its checkpoint.

Warnings (:class:`StiffKnotsWarning`, a ``UserWarning``) flag input that can be used but may not
be what the user meant: :class:`ChainWarning` (a chain that is not a unit-bond chain obeying the
bead rule, given to an analysis that assumes one).
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "ChainFormatError",
    "ChainGeometryError",
    "ChainWarning",
    "CheckpointError",
    "EmbeddingError",
    "EnergyBookkeepingError",
    "IdentificationError",
    "InvalidParameter",
    "ParameterConflict",
    "RunStopped",
    "StiffKnotsError",
    "StiffKnotsWarning",
    "TopologyChangedError",
    "UnknownKnotError",
    "UserInputError",
    "VerificationError",
    "WorkerError",
]


class StiffKnotsError(Exception):
    """Base class of every error stiffknots raises on purpose."""


class UserInputError(StiffKnotsError, ValueError):
    """A mistake of the user; the message says what was wrong and what would be right."""


class InvalidParameter(UserInputError):
    """A parameter outside its allowed range.

    Attributes
    ----------
    param : str
        The parameter's name in the Python API (``"force"``, ``"excess_length"``, ...).
    value
        The value given.
    allowed : str
        What is allowed, in words (``"a number > 0"``, ``"an integer in [8, 20000]"``).

    Notes
    -----
    The message reads ``"<param> must be <allowed>, got <value>"``; the command line re-words it
    with the option's name (:meth:`for_option`).
    """

    def __init__(self, param: str, value: Any, allowed: str, note: str = ""):
        self.param = param
        self.value = value
        self.allowed = allowed
        self.note = note
        super().__init__(self.message(param))

    def message(self, name: str) -> str:
        tail = f" ({self.note})" if self.note else ""
        if self.value is None:  # a parameter that is missing: "got None" says nothing
            return f"{name} must be {self.allowed}; it was not given{tail}"
        return f"{name} must be {self.allowed}, got {self.value!r}{tail}"

    def for_option(self, option: str) -> str:
        """The same message naming a command-line option (``--force``) instead."""
        return self.message(option)


class ParameterConflict(UserInputError):
    """Parameters that cannot be given together, or one that needs another.

    Attributes
    ----------
    params
        The parameters' names in the Python API (``("w", "w_over_L")``).
    template : str
        The message with one ``{}`` per parameter, in order.

    Notes
    -----
    The command line re-words it with the options' names (:meth:`message`).
    """

    def __init__(self, template: str, *params: str):
        self.template = template
        self.params = params
        super().__init__(self.message(lambda p: p))

    def message(self, name) -> str:
        """The message, each parameter spelled by ``name(param)`` (``"--w-over-L"``)."""
        return self.template.format(*(name(p) for p in self.params))


class UnknownKnotError(UserInputError):
    """A knot name that is not in the catalogue (or not a knot at all).

    The message says what was wrong and lists the closest valid names.
    """


class EmbeddingError(UserInputError):
    """A knot cannot be embedded with the requested parameters (the message says why, e.g.
    the least number of beads it needs)."""


class ChainFormatError(UserInputError):
    """A chain file that cannot be read: missing, corrupt, or not in the expected format."""


class CheckpointError(UserInputError):
    """A checkpoint that cannot be resumed: corrupt, truncated, or written by another run."""


class IdentificationError(StiffKnotsError, RuntimeError):
    """A knot invariant could not be computed (e.g. far too many crossings)."""


class VerificationError(StiffKnotsError, RuntimeError):
    """A result failed its verification: a bug of stiffknots, never a data point."""


class TopologyChangedError(VerificationError):
    """A run ended with a knot type different from the one it started with (never expected:
    the moves and the minimiser forbid strand passage by construction)."""


class EnergyBookkeepingError(VerificationError):
    """The incrementally tracked energy differs from the energy recomputed from scratch by more
    than its floating-point error bound."""


class ChainGeometryError(VerificationError):
    """A run ended with a broken chain (bond length, end clamping or exclusion violated)."""


class WorkerError(StiffKnotsError, RuntimeError):
    """A worker process died (a crash, the out-of-memory killer) before its job finished."""


class RunStopped(StiffKnotsError):  # noqa: N818 (not an error: a requested stop)
    """A run stopped on request (``stop_after`` chunks) after writing its checkpoint.

    Attributes
    ----------
    checkpoint
        Path of the checkpoint to resume from.
    step, n_steps : int
        Chunks done so far and chunks in the whole plan.
    """

    def __init__(self, checkpoint: Any, step: int, n_steps: int):
        super().__init__(f"stopped after chunk {step}/{n_steps}; resume from {checkpoint}")
        self.checkpoint = checkpoint
        self.step = step
        self.n_steps = n_steps


class StiffKnotsWarning(UserWarning):
    """Base class of the warnings stiffknots issues on purpose."""


class ChainWarning(StiffKnotsWarning):
    """A chain that is not what an analysis assumes: bonds not of unit length, or beads closer
    than the bead rule allows (:func:`stiffknots.checks.check` says which)."""
