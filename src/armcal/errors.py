"""Exceptions raised by armcal.

Every problem a user can fix (a malformed file, a plan that cannot identify the
parameters, an option out of range) raises :class:`ArmcalError` or one of its
subclasses.  The command line turns these into exit status 2 and a single line
``armcal: error: ...``; anything else is a bug and keeps its traceback.

A result that is computed but suspicious carries :class:`ArmcalWarning` records
(code and message); the command line prints each as ``armcal: warning: ...``
and the JSON lists them under ``warnings``.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["ArmcalError", "ArmcalWarning", "InputError", "NotIdentifiableError"]


class ArmcalError(ValueError):
    """A problem with the user's input or request, with a message that says how to fix it."""


class InputError(ArmcalError):
    """A file or option that cannot be read or does not validate.

    The message names the file and, where it applies, the row (1-based line of
    the file) and the column or key.
    """


class NotIdentifiableError(ArmcalError):
    """A plan whose Jacobian is rank deficient: some parameters cannot be identified.

    Attributes
    ----------
    combinations : list of str
        Human-readable parameter combinations that the plan cannot see, e.g.
        ``"dl3 - dl4"``.
    """

    def __init__(self, message: str, combinations: list[str] | None = None) -> None:
        super().__init__(message)
        self.combinations = list(combinations or [])


@dataclass(frozen=True)
class ArmcalWarning:
    """A result that is computed but suspicious: said on stderr and carried in the JSON.

    Attributes
    ----------
    code : str
        A stable, machine-readable key (``"ill-conditioned"``, ``"not-converged"``).
    message : str
        One line that says what is suspicious and what to try.

    Examples
    --------
    >>> ArmcalWarning("not-converged", "gauss-newton did not converge").to_dict()
    {'code': 'not-converged', 'message': 'gauss-newton did not converge'}
    """

    code: str
    message: str

    def to_dict(self) -> dict[str, str]:
        """The JSON form ``{code, message}``."""
        return {"code": self.code, "message": self.message}
