"""What a solve is asked to do besides the surface and the loads: :class:`SolverSettings`."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from ..core.backend import ARRAY_BACKENDS, get_backend
from ..core.quantities import cf_unit
from .effects import Effect, PlasticityCap
from .options import option
from .validation import check_positive, validate_boundary, validate_solver_args
from .workspace import ELASTIC_METHODS

#: Default iteration cap per load step.
DEFAULT_MAX_ITER = 10000


@dataclass(frozen=True)
class SolverSettings:
    """The elastic half-space, the iteration, its effects and the output's unit labels.

    Attributes
    ----------
    e_star : float
        Plane-strain modulus ``E* = E / (1 - nu**2)`` of the half-space [pressure], > 0.
    length : float or (float, float)
        A float ``L``: side of the square cell [length], > 0, for square heights only. A pair
        ``(Lx, Ly)``: the sides along x (axis 0) and y (axis 1) of a rectangular cell, each
        finite and > 0; pixels ``dx = Lx / nx`` and ``dy = Ly / ny``. ``(L, L)`` on an
        ``n x n`` grid is the float ``L``, bit for bit.
    tol : float
        Convergence tolerance in (0, 1) on the scale-free residual (docs/solver.md, "Convergence criterion").
    max_iter : int
        Iteration cap per load step, >= 1.
    threads : int
        FFTW threads, >= 1.
    boundary : {"periodic", "free"}
        ``"periodic"``: the cell is one period of an infinite periodic surface. ``"free"``: an
        isolated patch on an infinite half-space loaded only there (:class:`~.halfspace.FreeHalfSpace`).
    method : str or None
        The elastic iteration, one of :data:`~.workspace.ELASTIC_METHODS`; default ``"pk-fourier-f32"``
        (:data:`.options.DEFAULTS`, or what :func:`.options.set_options` set when the settings were made).
        None: that option when the solve starts.
    effects : tuple of Effect
        What acts on the iteration besides elasticity (:mod:`.effects`), e.g.
        ``(PlasticityCap(hardness),)``.
    length_unit, pressure_unit : str
        Labels of the output's units (:data:`roughcontact.core.quantities.LENGTH_UNITS` and
        ``PRESSURE_UNITS``); the numbers do not depend on them.
    array_backend : {"numpy", "cupy"} or None
        Where the iteration's fields live (:mod:`roughcontact.core.backend`): ``"numpy"`` on the
        host with pyFFTW; ``"cupy"`` on a CUDA GPU (``roughcontact[gpu]``), for the elastic
        solver without effects (periodic or free). Results agree within the solver's tolerance,
        not bit for bit (another FFT library). Default ``"numpy"`` (:data:`.options.DEFAULTS`, or
        what :func:`.options.set_options` set when the settings were made). None: that option when the
        solve starts.
    """

    e_star: float = 1.0
    length: float | tuple[float, float] = 1.0
    tol: float = 1e-8
    max_iter: int = DEFAULT_MAX_ITER
    threads: int = 1
    boundary: str = "periodic"
    method: str | None = field(default_factory=lambda: option("method"))
    effects: tuple[Effect, ...] = ()
    length_unit: str = "1"
    pressure_unit: str = "1"
    array_backend: str | None = field(default_factory=lambda: option("array_backend"))

    @classmethod
    def from_options(cls, settings: SolverSettings | None = None, **options) -> SolverSettings:
        """``settings`` (default: the defaults) with ``options`` replacing its fields.

        ``hardness`` is accepted as an option: a float adds ``PlasticityCap(hardness)`` to the
        effects, ``None`` adds nothing. An unknown option is a ``TypeError``, as for any function.
        """
        base = cls() if settings is None else settings
        if not isinstance(base, SolverSettings):
            raise ValueError(f"settings must be a SolverSettings or None, got {type(base).__name__}")
        hardness = options.pop("hardness", None)
        fields = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(options) - fields)
        if unknown:
            hint = ("; cluster statistics come from an observer: observers=[roughcontact.statistics.clusters."
                    "ClusterObserver(length)]") if "clusters" in unknown else ""
            raise TypeError(f"unexpected keyword argument(s) {unknown}; solver settings are {sorted(fields)}{hint}")
        settings = dataclasses.replace(base, **options)
        if hardness is not None:
            check_positive("hardness", hardness)
            settings = dataclasses.replace(settings, effects=(*settings.effects, PlasticityCap(hardness)))
        return settings

    def checked(self, shape) -> SolverSettings:
        """These settings validated for heights of ``shape``, the method resolved.

        Raises ``ValueError`` naming the field and its allowed range.
        """
        e_star, length, tol, max_iter, threads = validate_solver_args(
            self.e_star, self.length, self.tol, self.max_iter, self.threads, shape=shape)
        method = option("method") if self.method is None else self.method
        if method not in ELASTIC_METHODS:
            raise ValueError(f"method must be one of {ELASTIC_METHODS}, got {method!r}")
        effects = tuple(self.effects)
        for effect in effects:
            if not isinstance(effect, Effect):
                raise ValueError(f"effects must be Effect objects (roughcontact.solver.effects), got "
                                 f"{type(effect).__name__} {effect!r}")
        cf_unit(self.length_unit, self.pressure_unit)  # ValueError for a unit outside the declared sets
        backend = option("array_backend") if self.array_backend is None else self.array_backend
        _check_backend(backend, effects)
        return dataclasses.replace(self, e_star=e_star, length=length, tol=tol, max_iter=max_iter,
                                   threads=threads, boundary=validate_boundary(self.boundary),
                                   method=method, effects=effects, array_backend=backend)

    @property
    def hardness(self) -> float | None:
        """The lowest pressure cap of the effects [pressure], or None."""
        return min((e.pressure_cap for e in self.effects if e.pressure_cap is not None), default=None)


def _check_backend(backend: str, effects) -> None:
    """``backend`` is a known array backend, usable here, and runs what the settings ask for."""
    if backend not in ARRAY_BACKENDS:
        raise ValueError(f"array_backend must be one of {ARRAY_BACKENDS}, got {backend!r}")
    if backend != "numpy" and effects:
        names = ", ".join(type(e).__name__ for e in effects)
        raise ValueError(f"array_backend {backend!r} runs the elastic solver only, not the effects ({names}); "
                         "set array_backend to 'numpy' for a scene with effects")
    get_backend(backend)  # ValueError naming the remedy when CuPy or a GPU is missing
