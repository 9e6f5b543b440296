"""roughcontact: contact mechanics of representative rough surfaces.

Reproduces and extends Yastrebov, Anciaux & Molinari, "Contact between representative
rough surfaces", Phys. Rev. E 86, 035601 (2012).
"""

from importlib.metadata import PackageNotFoundError, version as _version

try:
    __version__ = _version("roughcontact")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0+unknown"

from .solver import solve_contact
from .surface import generate_surface

__all__ = ["__version__", "generate_surface", "solve_contact"]
