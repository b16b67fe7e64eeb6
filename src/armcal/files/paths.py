"""Output paths that never destroy anything, and writes that never leave half a file.

:func:`check_outputs` refuses, before any work, an output that is an input, a
directory, a special file or a link it was not meant to follow; every writer
writes a temporary file next to the target and renames it
(:func:`atomic_write`), so a failed run never leaves half a file; and
:func:`write_folder` makes an output folder only once all its files are complete.

A command that writes several files into a folder (``demo -o``, ``reproduce
-o``) names none of them on its command line, so it replaces only files it
wrote itself: :data:`MANIFEST` in the folder records each file armcal wrote and
a digest of its bytes, and a file of the same name that is not listed, or has
changed since, is the user's and is refused before any work.
"""

from __future__ import annotations

import errno
import hashlib
import os
import shutil
import stat
import sys
import tempfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

from ..errors import InputError
from .common import STDIO, PathArg, fail

__all__ = [
    "MANIFEST",
    "OutputFolder",
    "atomic_write",
    "check_outputs",
    "write_folder",
]


#: The file in an output folder that lists the files armcal wrote there, one
#: ``sha256  name`` line each (the format of ``sha256sum``, so ``sha256sum -c``
#: checks it).
MANIFEST = ".armcal-files"


def _digest(path: Path) -> str:
    """The SHA-256 of a file's bytes, as hex."""
    digest = hashlib.sha256()
    with path.open("rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _manifest(folder: Path) -> dict[str, str]:
    """Name to digest of the files armcal wrote into ``folder`` (empty if none or unreadable)."""
    try:
        lines = (folder / MANIFEST).read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        return {}
    entries = (line.split("  ", 1) for line in lines)
    return {name: digest for digest, name, *_ in (e for e in entries if len(e) == 2)}


def _ours(folder: Path, name: str, manifest: Mapping[str, str]) -> bool:
    """Whether ``folder/name`` is a regular file armcal wrote there and nobody changed."""
    path = folder / name
    if name not in manifest or not path.is_file():  # a link: the file it points to
        return False
    try:
        return _digest(path) == manifest[name]
    except OSError:
        return False


def _umask() -> int:
    umask = os.umask(0o022)  # the only portable way to read the umask
    os.umask(umask)
    return umask


def _file_mode(target: Path) -> int:
    """Permissions for ``target``: kept if it exists, else what ``open()`` would give.

    ``mkstemp`` creates files readable by the owner only (0600).
    """
    if target.exists():
        return target.stat().st_mode & 0o7777
    return 0o666 & ~_umask()


#: File kinds an output must never replace, with the ``stat`` test that finds them.
_SPECIAL_FILES = (
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


def _can_write_in(folder: Path) -> bool:
    return os.access(folder, os.W_OK | os.X_OK)


def _stat(path: Path) -> os.stat_result | None:
    """``os.stat`` (through links), or None when nothing is there."""
    try:
        return path.stat()
    except (FileNotFoundError, NotADirectoryError):
        return None


def _check_output_file(path: PathArg, fix: str = "give another path") -> Path:
    """The regular file a write to ``path`` replaces or makes; InputError if it must not.

    A symbolic link is followed to the file it points to (see :func:`atomic_write`).
    ``fix`` says what to do about a directory or a special file in the way.
    """
    if not os.fspath(path):
        raise InputError("an output file name is empty; give a file name")
    if os.fspath(path).endswith(("/", os.sep)):  # realpath would drop the slash
        raise fail(path, f"names a folder (it ends with a slash), expected a file; {fix}")
    real = Path(os.path.realpath(path))
    try:
        info = _stat(real)
    except OSError as exc:  # a link loop, a folder without search permission
        raise fail(path, f"cannot write: {exc.strerror}; {fix}") from None
    if info is not None:
        if stat.S_ISDIR(info.st_mode):
            raise fail(path, f"is a directory, expected a file; {fix}")
        for test, kind in _SPECIAL_FILES:
            if test(info.st_mode):
                raise fail(
                    path, f"is {kind}, not a regular file; armcal writes only regular files, {fix}"
                )
    folder = real.parent
    shown = f"folder {os.path.dirname(path) or '.'}"
    if os.path.islink(path):
        shown = f"folder {folder} of the link target"
    if not folder.exists():
        raise fail(path, f"cannot write: {shown} does not exist; create it first")
    if not folder.is_dir():
        raise fail(path, f"cannot write: {shown} is not a folder; give another path")
    if not _can_write_in(folder):
        raise fail(path, f"cannot write: {shown} is not writable; give another path")
    return real


def _check_output_folder(path: PathArg) -> Path:
    """The folder ``path`` (through links), if files can be written into it or it can be made."""
    if not os.fspath(path):
        raise InputError("an output folder name is empty; give a folder name")
    real = Path(os.path.realpath(path))
    try:
        info = _stat(real)
    except OSError as exc:
        raise fail(path, f"cannot use as the output folder: {exc.strerror}") from None
    if info is not None:
        if not stat.S_ISDIR(info.st_mode):
            raise fail(path, "is a file, expected a folder; give a folder name (made if missing)")
        if not _can_write_in(real):
            raise fail(path, "cannot write into the folder: not writable; give another folder")
        return real
    # The nearest existing folder as the user wrote it (through links, as the OS would).
    ancestor = next(parent for parent in Path(path).parents if os.path.lexists(parent))
    if not ancestor.is_dir():
        raise fail(path, f"cannot make the folder: {ancestor} is a file, not a folder")
    if not _can_write_in(ancestor):
        raise fail(path, f"cannot make the folder: {ancestor} is not writable")
    return real


def _same_file(real: Path, other: PathArg) -> bool:
    """Whether ``other`` names the file at the resolved path ``real`` (links and ./ included)."""
    if Path(os.path.realpath(other)) == real:
        return True
    try:
        return os.path.samefile(real, other)  # hard links, bind mounts
    except OSError:
        return False


@dataclass(frozen=True)
class OutputFolder:
    """An output folder and the names of the files a command writes into it.

    Attributes
    ----------
    path : str or path
        The folder; made (with its missing parents) when the files are written.
    files : tuple of str
        Names of the files written inside it.
    """

    path: PathArg
    files: tuple[str, ...]


def check_outputs(
    outputs: Mapping[str, PathArg | OutputFolder | None],
    inputs: Mapping[str, PathArg | None] | None = None,
) -> None:
    """Refuse, before any work, outputs that cannot or must not be written.

    A command calls this first, so that a bad output path costs no computing
    and leaves nothing behind.

    Parameters
    ----------
    outputs : mapping
        Option (``"-o"``, ``"--plot"``) to the file it writes, or to an
        :class:`OutputFolder`; None (an option not given) is skipped.
    inputs : mapping, optional
        Option (``"--plan"``) to the file the command reads; None is skipped.

    Raises
    ------
    InputError
        Naming the path, if an output file is a directory or a special file
        (FIFO, device, socket), is in a folder that is missing or not writable,
        is the same file as an input (compared through links, ``./`` and hard
        links), or is given for two outputs; if an output folder is a file
        or cannot be made; or if it holds a file of one of the names it will
        write that armcal did not write there (see :data:`MANIFEST`).

    Examples
    --------
    >>> check_outputs({"-o": "."})
    Traceback (most recent call last):
    ...
    armcal.errors.InputError: .: is a directory, expected a file; give -o another file name
    """
    # (option that writes it, path as given, resolved path, what to do if it clashes,
    #  why it must not be replaced though it could be: a file the user named none of)
    files: list[tuple[str, str, Path, str, str | None]] = []
    for option, output in outputs.items():
        if isinstance(output, OutputFolder):
            folder = _check_output_folder(output.path)
            if folder.is_dir():  # files already there must be replaceable, and ours
                fix = f"move it away or give {option} another folder"
                manifest = _manifest(folder)
                for name in output.files:
                    path = os.path.join(os.fspath(output.path), name)
                    real = _check_output_file(path, fix)
                    theirs = None
                    if os.path.lexists(path) and not _ours(folder, name, manifest):
                        theirs = (
                            "exists and armcal did not write it (or it has changed since); "
                            f"{option} {os.fspath(output.path)} would replace it; {fix} "
                            "(a new or empty one)"
                        )
                    files.append((option, path, real, fix, theirs))
        elif output is not None and os.fspath(output) == STDIO:
            continue  # stdout: the command checks that it is the only one
        elif output is not None:
            fix = f"give {option} another file name"
            files.append((option, os.fspath(output), _check_output_file(output, fix), fix, None))
    for k, (option, path, real, fix, theirs) in enumerate(files):
        for input_option, source in (inputs or {}).items():
            if source is not None and _same_file(real, source):
                raise fail(
                    path,
                    f"is the input {input_option} {os.fspath(source)}; writing it would "
                    f"destroy the input; {fix}",
                )
        for other_option, other, other_real, *_ in files[:k]:
            if other_real == real:
                raise fail(
                    path,
                    f"given for two outputs ({other_option} {other} and {option} {path}); "
                    "give each its own file name",
                )
        if theirs is not None:
            raise fail(path, theirs)


#: Characters of a text encoded and written at once (:func:`atomic_write`).
WRITE_CHUNK = 1 << 20


def atomic_write(path: PathArg, content: str | bytes | Callable[[BinaryIO], None]) -> None:
    """Write ``content`` to ``path`` through a temporary file and a rename.

    The temporary file is made next to the file it replaces and renamed over it
    only once complete, so a failed or interrupted write leaves the old file
    (or nothing) and no temporary file.  An existing file keeps its
    permissions; a new one gets ``0666`` minus the umask.

    A symbolic link is written through, as a shell's ``>`` would: the file it
    points to (at the end of the chain of links; made if missing) is replaced
    atomically and the link is kept.  A directory or a special file (FIFO,
    character or block device, socket) is never replaced.

    Parameters
    ----------
    path : str or path
        Target file; its folder must exist.  An existing file is replaced.
        :data:`STDIO` (``-``) writes to stdout instead.
    content : str, bytes or callable
        UTF-8 text, bytes, or a function that writes bytes to the open binary
        handle (e.g. ``lambda handle: fig.savefig(handle, format="png")``).

    Raises
    ------
    InputError
        If the folder does not exist or is not writable, or ``path`` is a
        directory or a special file.
    """
    if os.fspath(path) == STDIO:
        if isinstance(content, str):
            sys.stdout.write(content)
        elif isinstance(content, bytes):
            sys.stdout.flush()
            sys.stdout.buffer.write(content)
        else:
            sys.stdout.flush()
            content(sys.stdout.buffer)
        sys.stdout.flush()
        return
    target = _check_output_file(path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    except OSError as exc:
        raise fail(path, f"cannot write: {exc.strerror}") from None
    try:
        with os.fdopen(fd, "wb") as handle:
            if isinstance(content, str):
                # In pieces: a 10^5-row file encoded at once is a second copy of it.
                for start in range(0, len(content), WRITE_CHUNK):
                    handle.write(content[start : start + WRITE_CHUNK].encode("utf-8"))
            elif isinstance(content, bytes):
                handle.write(content)
            else:
                content(handle)
        os.chmod(tmp, _file_mode(target))
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _move_into_place(staged: Path, path: Path) -> None:
    """Replace ``path`` (through links) by the complete file ``staged``, keeping its mode."""
    target = _check_output_file(path)
    os.chmod(staged, _file_mode(target))
    try:
        os.replace(staged, target)
    except OSError as exc:
        if exc.errno != errno.EXDEV:
            raise
        atomic_write(target, staged.read_bytes())  # a link into another file system


def write_folder(path: PathArg, files: Mapping[str, str | Callable[[Path], None]]) -> Path:
    """Write ``files`` into the folder ``path``: every file complete, or nothing new.

    Every file is first written into a hidden temporary folder.  A new folder
    (with any missing parent) then appears by one rename, once every file is
    complete; in an existing folder the files are renamed into place one by one
    (as :func:`atomic_write`: through links, keeping modes) and other files
    there are left alone.  On a failure or an interrupt before that, the
    temporary folder is removed and nothing is left behind.

    Parameters
    ----------
    path : str or path
        The output folder; links are followed.
    files : mapping
        File name to UTF-8 text, or to a function that writes the file at the
        path it is given (e.g. ``lambda target: save_figure(fig, target)``).

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    InputError
        If ``path`` is a file or cannot be made, or holds a file of one of the
        names that must not be replaced (see :func:`check_outputs`).

    Notes
    -----
    :data:`MANIFEST` in the folder lists every file written (and keeps the
    entries of earlier runs for other names), so that a later run may replace
    these files and no others.
    """
    folder = _check_output_folder(path)
    exists = folder.is_dir()
    top = folder  # the outermost folder to make
    while not exists and not os.path.lexists(top.parent):
        top = top.parent
    stage = Path(
        tempfile.mkdtemp(
            prefix=".armcal-" if exists else f".{top.name}.",
            suffix=".tmp",
            dir=folder if exists else top.parent,
        )
    )
    try:
        inner = stage if exists else stage / folder.relative_to(top)
        inner.mkdir(parents=True, exist_ok=True)
        for name, content in files.items():
            if isinstance(content, str):
                atomic_write(inner / name, content)
            else:
                content(inner / name)
        manifest = _manifest(folder) if exists else {}
        manifest.update({name: _digest(inner / name) for name in files})
        listing = "".join(f"{digest}  {name}\n" for name, digest in sorted(manifest.items()))
        atomic_write(inner / MANIFEST, listing)
        if exists:
            for name in (*files, MANIFEST):
                _move_into_place(inner / name, folder / name)
        else:
            os.chmod(stage, 0o777 & ~_umask())  # mkdtemp makes it 0700
            if os.path.lexists(top):
                raise fail(path, f"cannot make the folder: {top} appeared while armcal ran")
            os.rename(stage, top)
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise
    if exists:
        shutil.rmtree(stage, ignore_errors=True)
    return Path(path)
