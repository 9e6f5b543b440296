"""The installed package's version, as every file it writes records it."""

from importlib.metadata import PackageNotFoundError, version as _version

try:
    __version__ = _version("roughcontact")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0+unknown"
