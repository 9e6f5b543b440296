"""Surface sources: where a scene's surfaces come from, one module each, found by name (:data:`SOURCES`).

Adding a source: one module in this package with a :class:`Source` subclass (for named,
non-periodic patches a :class:`PatchSource`) decorated with :func:`register` (every module here is
imported below, so the registry finds it), its config block in the schema (a property of
``scene``, listed in the schema's ``if`` that exempts a scene from the generator's keys) and its
rows in config/README.md. :mod:`.base` states what a source supplies; :func:`source_of` gives a
scene's.
"""

import importlib
import pkgutil

from .base import SOURCES, Source, for_case, for_dims, register, source_of
from .patches import PatchSource

# The generator and the measured files first: registry order is the order of messages and of
# :func:`for_dims` (the measured source stands for every patch source there).
for _name in ["generated", "measured", *sorted(m.name for m in pkgutil.iter_modules(__path__))]:
    importlib.import_module(f"{__name__}.{_name}")

__all__ = ["SOURCES", "PatchSource", "Source", "for_case", "for_dims", "register", "source_of"]
