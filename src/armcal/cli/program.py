"""The ``armcal`` program: parse the arguments, check every path, run the command.

Exit status: 0 on success, 2 for bad input (one ``armcal: error: ...`` line on
stderr, no traceback, no output file), 130 when interrupted (Ctrl-C; one
``armcal: interrupted`` line), 1 for bugs.  Output paths are checked before any
work (:func:`armcal.files.check_outputs`).
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable, Sequence

from ..choices import BUILTIN_ROBOTS
from ..errors import ArmcalError, unique_warnings
from ..files import STDIO, OutputFolder, check_outputs
from ..files.common import forget_stdin
from ..formats import FIGURE_FORMATS
from ..progress import Elapsed
from .output import CLI_ACTIONS, print_warnings
from .parser import build_parser

__all__ = ["main"]


#: Options whose destination is not their flag's name (``--from`` is a Python keyword).
_FLAGS = {"output": "-o", "original": "--from"}


def _option(dest: str) -> str:
    return _FLAGS.get(dest, "--" + dest.replace("_", "-"))


def _check_stdio(args: argparse.Namespace, inputs: dict, outputs: dict) -> None:
    """``-`` reads stdin (one input) and writes stdout (one file output, instead of the report)."""
    piped = [option for option, path in inputs.items() if path == STDIO]
    if len(piped) > 1:
        raise ArmcalError(
            f"{' and '.join(piped)} both read '-' (stdin); pipe in one of them and give the "
            "other a file name"
        )
    to_stdout = [option for option, path in outputs.items() if path == STDIO]
    if not to_stdout:
        return
    if getattr(args, "folder_files", None) is not None:
        raise ArmcalError(f"{to_stdout[0]} -: a folder cannot go to stdout; give a folder name")
    if "--plot" in to_stdout:
        raise ArmcalError(
            "--plot -: a figure cannot go to stdout; give a file name ending in "
            + ", ".join(FIGURE_FORMATS)
        )
    if len(to_stdout) > 1:
        raise ArmcalError(
            f"{' and '.join(to_stdout)} both write '-' (stdout); give all but one a file name"
        )
    if getattr(args, "json", False):
        raise ArmcalError(
            f"--json and {to_stdout[0]} - both write stdout; drop --json (the file is the "
            "output) or give a file name"
        )
    args.stdout_taken = True


def _check_figure(path: str | None) -> None:
    """A figure's format is its suffix's (:data:`FIGURE_FORMATS`); any other suffix is refused."""
    if path is None or path == STDIO:
        return
    suffix = os.path.splitext(path)[1].lower()
    if suffix not in FIGURE_FORMATS:
        known = ", ".join(FIGURE_FORMATS)
        raise ArmcalError(
            f"--plot {path}: "
            + (f"'{suffix}' is not a figure format armcal writes" if suffix else "no suffix")
            + f"; the suffix names the format: give a name ending in {known}"
        )


def _check_paths(args: argparse.Namespace) -> None:
    """Refuse the command's unusable output paths before it does any work."""
    _check_figure(getattr(args, "plot", None))
    inputs = {_option(dest): getattr(args, dest) for dest in getattr(args, "inputs", ())}
    if inputs.get("--robot") in BUILTIN_ROBOTS:
        del inputs["--robot"]  # a name, not a file
    names = getattr(args, "folder_files", None)  # a folder's files, named by the command
    folder_files: tuple[str, ...] = () if names is None else names()
    outputs: dict[str, str | OutputFolder | None] = {}
    for dest in getattr(args, "outputs", ()):
        path = getattr(args, dest)
        outputs[_option(dest)] = (
            OutputFolder(path, folder_files)
            if folder_files and path is not None and path != STDIO
            else path
        )
    _check_stdio(args, inputs, outputs)
    check_outputs(outputs, inputs)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``armcal`` program; returns the exit status."""
    argv = sys.argv[1:] if argv is None else list(argv)
    if not argv:  # a first try: the commands, then why nothing ran (exit 2 for scripts)
        build_parser().print_help()
        print("armcal: error: no command given; pick one of the commands above", file=sys.stderr)
        return 2
    args = None
    forget_stdin()  # this run's stdin, not an earlier run's in the same process
    try:
        args = build_parser().parse_args(argv)
        _check_paths(args)
        run: Callable[[argparse.Namespace], None] = args.run
        with Elapsed(f"armcal {args.command}"):  # a line on a terminal after 2 s of work
            run(args)
    except ArmcalError as exc:
        # The robot file's warnings (radian limits, lengths in metres) often explain the
        # error that stopped the command before its report: print them first.
        print_warnings(unique_warnings(getattr(args, "loaded_warnings", ())))
        print(f"armcal: error: {exc.render(CLI_ACTIONS)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # Ctrl-C: writers have removed their temporary files
        if sys.stderr.isatty():
            sys.stderr.write("\n")  # after a progress bar or the terminal's ^C
        print("armcal: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. `armcal synthesize ... | head`
        sys.stderr.close()
        return 0
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
