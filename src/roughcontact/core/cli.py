"""The edge of every ``python -m roughcontact...`` command: bad input ends in one line and exit status 2.

A command's own checks name the file and what is wrong (``ValueError``, ``OSError``; the package's
:class:`roughcontact.pipeline.io.InputFileError` is a ``ValueError``); :func:`input_errors` turns them into
``error: <message>`` on one line of stderr and exit status 2, never a traceback. Errors of other kinds
are bugs and keep their traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import json
from pathlib import Path

#: Exit status of a command given bad input (argparse's own for a bad command line).
BAD_INPUT = 2


def one_line(exc: BaseException) -> str:
    """``exc``'s message on one line (an OSError's with its file)."""
    if isinstance(exc, OSError) and exc.filename is not None and str(exc.filename) not in str(exc.strerror):
        text = f"{exc.filename}: {exc.strerror or exc}"
    else:
        text = str(exc) or type(exc).__name__
    return " ".join(text.split())


@contextlib.contextmanager
def input_errors(ap: argparse.ArgumentParser):
    """Run the body; a ``ValueError`` or ``OSError`` ends the command with one line ``error: ...`` and exit 2."""
    try:
        yield
    except (ValueError, OSError) as exc:
        ap.exit(BAD_INPUT, f"error: {one_line(exc)}\n")


def require_folder(path: str | Path, what: str) -> Path:
    """``path`` if it is an existing folder, else ``ValueError`` naming it and ``what`` it should be."""
    path = Path(path)
    if not path.is_dir():
        state = "is a file, not a folder" if path.exists() else "does not exist"
        raise ValueError(f"{path}: {state}; give {what}")
    return path


def require_files(folder: str | Path, names, what: str) -> None:
    """``ValueError`` naming the first of ``names`` missing from ``folder`` (``what``: what holds them)."""
    folder = Path(folder)
    missing = [name for name in names if not (folder / name).is_file()]
    if missing:
        raise ValueError(f"{folder / missing[0]}: no such file ({len(missing)} of {len(list(names))} missing: "
                         f"{', '.join(missing)}); {what}")


def read_json_object(path: str | Path, required: dict[str, type]) -> dict:
    """The JSON object in ``path`` with each ``required`` key of its type, else ``ValueError`` naming the file."""
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not valid JSON at line {exc.lineno}, column {exc.colno}: {exc.msg}") from None
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not a JSON text file (not UTF-8)") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path}: holds a JSON {type(data).__name__}, not an object with the keys "
                         f"{', '.join(required)}")
    for key, kind in required.items():
        value = data.get(key)
        if not isinstance(value, kind) or isinstance(value, bool):
            raise ValueError(f"{path}: {key!r} is {value!r}, not a {kind.__name__}")
    return data
