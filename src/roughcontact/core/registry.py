"""Registries of classes found by name (surface sources, solver effects)."""

from __future__ import annotations

from collections.abc import Callable


def registrar(table: dict[str, type], kind: str) -> Callable[[type], type]:
    """A class decorator that puts a class into ``table`` under its ``name``.

    ``kind`` names what the table holds in the error for an empty or taken name.
    """
    def register(cls: type) -> type:
        """Class decorator: make ``cls`` available to scenes under ``cls.name``."""
        if not cls.name or cls.name in table:
            raise ValueError(f"{kind} name {cls.name!r} is empty or already registered")
        table[cls.name] = cls
        return cls

    return register
