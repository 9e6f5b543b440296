"""Process-wide solver options: the elastic iteration and array backend a new :class:`~.settings.SolverSettings` takes.

The defaults live on :class:`~.settings.SolverSettings` itself: ``SolverSettings().method`` is
``"pk-fourier-f32"`` and ``SolverSettings().array_backend`` is ``"numpy"`` (:data:`DEFAULTS`). Library code
that wants another passes it, as a field or a keyword of :func:`~.solve.solve_contact`::

    solve_contact(h, loads, method="pk")

:func:`set_options` changes the default a settings object made inside its block takes, as
``xarray.set_options`` does, for code that cannot pass settings down to every solve: the test suite run
on a GPU (``ROUGHCONTACT_ARRAY_BACKEND=cupy``, read by ``tests/conftest.py``; ``benchmarks/gpu/run.sh``)
and a benchmark that times each iteration on the same calls::

    with set_options(array_backend="cupy"):
        solve_contact(h, loads)          # every solve that names no backend runs on the GPU

Called without ``with``, it sets the options until the process ends (the test suite's GPU run).
"""

from __future__ import annotations

from ..core.backend import ARRAY_BACKENDS
from .workspace import ELASTIC_METHODS

#: The options' values when nothing sets them: the default elastic iteration (one of
#: :data:`~.workspace.ELASTIC_METHODS`) and array backend (one of :data:`~roughcontact.core.backend.ARRAY_BACKENDS`).
DEFAULTS = {"method": "pk-fourier-f32", "array_backend": "numpy"}
#: The allowed values of each option.
ALLOWED = {"method": ELASTIC_METHODS, "array_backend": ARRAY_BACKENDS}

_current = dict(DEFAULTS)


def get_options() -> dict[str, str]:
    """The current options (a copy): ``{"method": ..., "array_backend": ...}``."""
    return dict(_current)


def option(name: str) -> str:
    """The current value of option ``name`` (``"method"`` or ``"array_backend"``)."""
    return _current[name]


class set_options:  # noqa: N801 - used as a function, as xarray.set_options
    """Set solver options: for a ``with`` block (restored after it), or until the process ends.

    Parameters
    ----------
    method : str, optional
        The elastic iteration of a settings object that names none, one of :data:`~.workspace.ELASTIC_METHODS`.
    array_backend : str, optional
        Where such a solve's fields live, one of :data:`~roughcontact.core.backend.ARRAY_BACKENDS`.

    Raises
    ------
    TypeError
        For an unknown option.
    ValueError
        For a value outside the option's allowed ones.
    """

    def __init__(self, **options: str):
        unknown = sorted(set(options) - set(ALLOWED))
        if unknown:
            raise TypeError(f"unknown solver option(s) {unknown}; the options are {sorted(ALLOWED)}")
        for name, value in options.items():
            if value not in ALLOWED[name]:
                raise ValueError(f"solver option {name} must be one of {ALLOWED[name]}, got {value!r}")
        self._previous = {name: _current[name] for name in options}
        _current.update(options)

    def __enter__(self) -> set_options:
        return self

    def __exit__(self, *exc) -> None:
        _current.update(self._previous)
