"""The ``armcal`` command line (``armcal COMMAND --help``; ``python -m armcal``).

- :mod:`.program`: the program, its exit status and the paths it checks first;
- :mod:`.parser` and :mod:`.options`: the table of commands, their options and types;
- :mod:`.help`: every command's description, files and example;
- :mod:`.commands`: each command, thin over :mod:`armcal.workflow`;
- :mod:`.output`: what is printed, and the warnings in the command line's words.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..lazy import exports

if TYPE_CHECKING:
    from .output import CLI_ACTIONS
    from .parser import build_parser
    from .program import main

# Out of mypy's sight: it sees the names imported above, and still flags a misspelt one.
if not TYPE_CHECKING:
    __getattr__, __dir__ = exports(
        __name__,
        {
            ".output": ("CLI_ACTIONS",),
            ".parser": ("build_parser",),
            ".program": ("main",),
        },
    )

__all__ = ["CLI_ACTIONS", "build_parser", "main"]
