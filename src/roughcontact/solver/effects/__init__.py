"""Effects that act on the contact iteration, one module each, found by name (:data:`EFFECTS`).

Adding an effect: one module here with an :class:`Effect` subclass decorated with
:func:`register`, imported below; its config keys in the schema (``contact.effects.<name>``)
and config/README.md. :mod:`.base` states what an effect supplies.
"""

from .adhesion import Adhesion
from .base import EFFECTS, Effect, effects_from_config, register
from .plasticity import PlasticityCap

__all__ = ["EFFECTS", "Adhesion", "Effect", "PlasticityCap", "effects_from_config", "register"]
