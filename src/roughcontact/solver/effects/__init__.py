"""Effects that act on the contact iteration, one module each, found by name (:data:`EFFECTS`).

Adding an effect: one module in this package with an :class:`Effect` subclass decorated with
:func:`register` (every module here is imported below, so the registry finds it), its config
keys in the schema (``contact.effects.<name>``) and a row in config/README.md. :mod:`.base`
states what an effect supplies, what it declares to the pipeline (the gap iteration, tension, whether
the contact evolution law still applies, the report's figures and tables) and its cross-field rules:
the pipeline asks those, and never tests an effect's name.
"""

import importlib
import pkgutil

from .base import EFFECTS, Effect, effects_from_config, register

for _module in pkgutil.iter_modules(__path__):
    importlib.import_module(f"{__name__}.{_module.name}")

from .adhesion import Adhesion  # noqa: E402  (the public names; registered by the loop above)
from .plasticity import PlasticityCap  # noqa: E402

__all__ = ["EFFECTS", "Adhesion", "Effect", "PlasticityCap", "effects_from_config", "register"]
