"""roughcontact: contact mechanics of representative rough surfaces.

Reproduces and extends Yastrebov, Anciaux & Molinari, "Contact between representative
rough surfaces", Phys. Rev. E 86, 035601 (2012).
"""

from .core.version import __version__
from .solver import solve_contact
from .surfaces.synthetic import generate_surface

__all__ = ["__version__", "generate_surface", "solve_contact"]
