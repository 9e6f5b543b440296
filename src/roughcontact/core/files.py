"""Atomic file output and file hashes: the writing every layer shares.

Every output (NetCDF, CSV, Markdown, figures, FFTW wisdom) goes through :func:`atomic_output` (or
:func:`write_text_atomic` for text): the target either keeps its previous complete content or gets the
new complete content, and it gets the mode the umask gives to a newly created file
(``0o666 & ~umask``, e.g. 0644 under umask 022).
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import re
import secrets
from collections.abc import Iterator
from pathlib import Path


class OutputFileError(OSError):
    """An output could not be written (full disk, no permission); nothing partial remains."""


def file_sha256(path: str | os.PathLike) -> str:
    """Hex SHA-256 of a file's bytes, read in blocks (raises OSError if it cannot be read)."""
    with open(path, "rb") as fh:
        return hashlib.file_digest(fh, "sha256").hexdigest()


def current_umask() -> int:
    """The process' umask, read without changing it where the OS allows.

    Linux reports it in ``/proc/self/status``; elsewhere it is read by setting and
    restoring it (``os.umask`` has no read-only form).
    """
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _stale_temporaries(path: Path) -> list[Path]:
    # Names made by atomic_output (and by the mkstemp calls of earlier versions):
    # ".<name>.<token>.tmp", the token without dots, so another target's temporaries
    # (".<name>.x.<token>.tmp" belongs to "<name>.x") never match.
    pattern = re.compile(rf"\.{re.escape(path.name)}\.[A-Za-z0-9_]+\.tmp")
    try:
        entries = list(path.parent.iterdir())
    except FileNotFoundError:
        return []
    return [p for p in entries if pattern.fullmatch(p.name)]


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike) -> Iterator[Path]:
    """Write ``path`` atomically: yield a temporary path to write, then rename it over ``path``.

    The temporary file ``.<name>.<random>.tmp`` is created (empty) in the target's
    folder, so the final :func:`os.replace` stays on one file system and is atomic:
    readers, and a job killed at any moment, see either the previous complete file (or
    none) and never a partial one. The parent folder is created. On success the file
    gets mode ``0o666 & ~umask``, as a plain ``open(path, "w")`` would give it (not
    the 0600 of :func:`tempfile.mkstemp`), and replaces the target. If the body raises,
    the temporary file is removed and the target left as it was. Temporaries of this
    target left by a killed earlier job are removed first: each target has one writer
    (its workflow job), so they cannot belong to a live write.

    The writer may reopen, truncate or recreate the temporary path. This protects
    against the writing process dying, not against power loss (no ``fsync``).

    Example::

        with atomic_output("out/table.csv") as tmp:
            frame.to_csv(tmp)
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    for stale in _stale_temporaries(path):
        stale.unlink(missing_ok=True)
    while True:
        tmp = path.parent / f".{path.name}.{secrets.token_hex(6)}.tmp"
        try:
            # O_EXCL: never reuse an existing file; mode 0o666 lets the umask decide.
            os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
            break
        except FileExistsError:  # pragma: no cover - 48 random bits
            continue
    try:
        yield tmp
        # The writer may have recreated the file with another mode (mkstemp-style).
        os.chmod(tmp, 0o666 & ~current_umask())
        os.replace(tmp, path)
    except OSError as exc:
        # A full disk, a quota, a read-only folder: often reported without the file's
        # name, so name it here, once.
        tmp.unlink(missing_ok=True)
        raise OutputFileError(f"{path}: could not be written ({exc}); nothing was left in its place") from exc
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def check_writable(path: str | os.PathLike, what: str = "the output") -> Path:
    """``path`` as a :class:`~pathlib.Path` if a file can be written there, else ``ValueError`` naming it.

    What a tool calls before its work, so that a bad output path fails in a second, not after an hour's
    solve: ``path`` must not be a folder, and the folder it goes in must be writable, or creatable
    (:func:`atomic_output` creates it) under its nearest existing ancestor. Writability is probed by
    creating and removing a temporary file there: permission bits say nothing for root, and a read-only
    mount shows only when written. Nothing is left behind.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     check_writable(f"{d}/new/contact.nc").name
    'contact.nc'
    """
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{path}: is a folder; give {what}'s file name (e.g. {path / 'contact.nc'})")
    folder = path.parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    if not folder.is_dir():
        raise ValueError(f"{path}: cannot be written: {folder} is a file, not a folder; give {what} another path")
    try:
        fd, probe = _probe(folder)
    except OSError as exc:
        reason = exc.strerror or exc
        raise ValueError(f"{path}: cannot be written ({folder}: {reason}); give {what} a writable folder") from None
    os.close(fd)
    os.unlink(probe)
    return path


def _probe(folder: Path) -> tuple[int, str]:
    """A new empty file in ``folder`` (its descriptor and path), as :func:`atomic_output` would create one."""
    while True:
        probe = os.path.join(folder, f".write-probe.{secrets.token_hex(6)}.tmp")
        try:
            return os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600), probe
        except FileExistsError:  # pragma: no cover - 48 random bits
            continue


def write_text_atomic(path: str | os.PathLike, text: str, *, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` through :func:`atomic_output`; returns the path."""
    with atomic_output(path) as tmp, open(tmp, "w", encoding=encoding) as fh:
        fh.write(text)
    return Path(path)
