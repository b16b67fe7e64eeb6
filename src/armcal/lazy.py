"""A package's names, imported from their modules on first use (PEP 562).

``import armcal`` then costs the package's own file and nothing more: the first
``armcal.identify`` (or ``from armcal.doe import design``) imports the one module
that defines the name, and a command imports only what it uses.  A package lists
where each of its names lives (:func:`exports`) and imports the same names under
``if TYPE_CHECKING:``, so that mypy and editors see them as before.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping

__all__ = ["exports"]


def exports(
    package: str, homes: Mapping[str, tuple[str, ...]]
) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """The module ``__getattr__`` and ``__dir__`` of a package whose names live in its modules.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    homes : mapping of str to tuple of str
        Each module, relative to the package (``".calibrate"``), and the names the package
        takes from it.

    Returns
    -------
    getattr : callable
        The package's ``__getattr__``: a listed name is imported from its module and kept
        on the package (the next look-up is a plain attribute); any other public name is
        the package's submodule of that name, as ``import armcal.models`` gives it (an
        eager package had bound every submodule it imported); else AttributeError.
    dir : callable
        The package's ``__dir__``: its attributes and every listed name.

    Examples
    --------
    >>> getattr_, dir_ = exports("armcal", {".errors": ("ArmcalError",)})
    >>> getattr_("ArmcalError").__name__
    'ArmcalError'
    >>> "ArmcalError" in dir_()
    True
    """
    where = {name: module for module, names in homes.items() for name in names}

    def getattr_(name: str) -> object:
        module = where.get(name)
        if module is not None:
            value = getattr(importlib.import_module(module, package), name)
            setattr(sys.modules[package], name, value)
            return value
        missing = AttributeError(f"module {package!r} has no attribute {name!r}")
        if name.startswith("_"):  # dunder probes (__wrapped__, __path__ ...): no submodule
            raise missing
        try:
            return importlib.import_module(f"{package}.{name}")
        except ModuleNotFoundError as exc:
            if exc.name != f"{package}.{name}":  # the submodule exists, an import in it failed
                raise
            raise missing from None

    def dir_() -> list[str]:
        return sorted({*vars(sys.modules[package]), *where})

    return getattr_, dir_
