"""The ``armcal`` command line (``armcal COMMAND --help``; ``python -m armcal``).

- :mod:`.program`: the program, its exit status and the paths it checks first;
- :mod:`.parser` and :mod:`.options`: the table of commands, their options and types;
- :mod:`.help`: every command's description, files and example;
- :mod:`.commands`: each command, thin over :mod:`armcal.workflow`;
- :mod:`.output`: what is printed, and the warnings in the command line's words.
"""

from __future__ import annotations

from .output import CLI_ACTIONS
from .parser import build_parser
from .program import main

__all__ = ["CLI_ACTIONS", "build_parser", "main"]
