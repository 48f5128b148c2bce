"""The smach exception hierarchy (names and meanings as upstream)."""
from __future__ import annotations

__all__ = ["InvalidStateError", "InvalidTransitionError", "InvalidConstructionError",
           "InvalidUserCodeError", "UndeclaredKeyError"]


class InvalidStateError(Exception):
    """A state is missing, duplicated, or was given a wrong specification."""


class InvalidTransitionError(Exception):
    """A transition refers to an unknown outcome or target, or a state returned an unbound outcome."""


class InvalidConstructionError(Exception):
    """A container was built wrongly (e.g. ``add`` called with no container open)."""


class InvalidUserCodeError(Exception):
    """User code (a state's execute or a callback) raised, or broke the userdata contract."""


class UndeclaredKeyError(InvalidUserCodeError, KeyError):
    """A state read a userdata key it did not declare as input.

    Upstream raises InvalidUserCodeError for attribute access and KeyError for item access; this class is
    both, so either ``except`` clause written for the original keeps working.
    """

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""
