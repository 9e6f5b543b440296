"""A reference iteration of the kind Yastrebov et al. (2012) used: Stanley & Kato's (1997).

Not the default solver, and not used by any pipeline stage but the κ-gap study
(:mod:`roughcontact.studies.kappa_gap`): it answers one question, whether a solver of the paper's
family, stopped by a rule of its kind, gives a different contact area from ours.

The method (H. M. Stanley and T. Kato, "An FFT-based method for rough surface contact",
J. Tribol. 119, 481-485, 1997), as reconstructed here from its published description (the
article's text was not available to this project; the paper's "minor improvements" are
not described anywhere): the unknown is the *displacement* of the elastic surface, not the
pressure; the pressure follows from it in Fourier space, where the periodic half-space is
diagonal, and the contact constraints are imposed in real space, so each iteration moves
between the two domains once. With ``z`` the height of the deformed elastic surface
(the rigid surface ``h`` below it; highest points touch first, as in the main solver) and
``p0`` the applied mean pressure, the potential energy

    Pi(z) = 1/2 z.Kz + p0 sum(z),   K(q) = E* |q| / 2  (0 at q = 0),

is minimised over ``z >= h`` (no interpenetration). Its gradient is the pressure the
current shape implies, ``p(z) = p0 + F^-1[K(q) z(q)]``, and the iteration is the projected
gradient (a relaxation of the displacement)

    z <- max(z - omega p(z) / K_max, h),     K_max = max_q E* |q| / 2,

``omega`` the relaxation factor (stable for 0 < omega < 2). At the fixed point the
nodes off the rigid surface carry ``p = 0`` and the nodes on it ``p >= 0``: the contact
problem's solution, the same unique one the main solver finds. The contact set is
``{z = h}``; the contact pressure ``max(p(z), 0)`` on it, 0 elsewhere.

*Its stopping rule.* A displacement method does not hold the load exactly before it has
converged: the pressure on the contact set carries ``mean(p_c) != p0``. The rule of this
kind stops when the carried load matches the applied one, ``|mean(p_c) - p0| <= tol p0``,
and the displacement has stopped moving, ``max|dz| <= tol s`` (``s`` the rms height), at
two successive checks. Both are what such a code can watch cheaply; neither bounds the
complementarity directly, which is why :func:`solve_stanley_kato` also reports the main
solver's scale-free residual of the returned state.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ...core.fft import get_fft, wavenumbers

#: Default relaxation factor omega (plain projected gradient).
OMEGA = 1.0
#: Iterations between two evaluations of the stopping rule.
CHECK_EVERY = 10


@dataclass(frozen=True)
class StanleyKatoStep:
    """One load step of the reference iteration.

    ``pressure`` [pressure] and ``gap`` ``z - h`` [length] are ``(n, n)`` arrays;
    ``area_fraction`` counts the nodes on the rigid surface; ``load_error`` is
    ``|mean(p_c) - p0| / p0``; ``stopped`` says whether the stopping rule ended the step
    (else ``max_iter`` did).
    """

    p0: float
    pressure: np.ndarray
    gap: np.ndarray
    area_fraction: float
    load_error: float
    iterations: int
    stopped: bool
    wall_time: float


class StanleyKato:
    """The displacement iteration on one periodic square surface ``h`` of side ``length``."""

    def __init__(self, heights, *, e_star: float = 1.0, length: float = 1.0, omega: float = OMEGA):
        h = np.asarray(heights, dtype=float)
        if h.ndim != 2 or h.shape[0] != h.shape[1] or h.shape[0] < 4 or not np.all(np.isfinite(h)):
            raise ValueError(f"heights must be a finite square array of side >= 4, got shape {h.shape}")
        if not 0.0 < omega < 2.0:
            raise ValueError(f"omega (relaxation factor) must lie in (0, 2), got {omega!r}")
        if not (e_star > 0 and length > 0):
            raise ValueError(f"e_star and length must be > 0, got {e_star!r}, {length!r}")
        self.h = h - h.mean()
        self.scale = float(np.sqrt(np.mean(self.h**2))) or 1.0
        kx, ky = wavenumbers(h.shape, length)
        self.stiffness = 0.5 * e_star * 2.0 * np.pi * np.hypot(kx, ky)
        self.step_size = omega / float(self.stiffness.max())
        self.fft = get_fft(h.shape)
        self.z = np.full_like(self.h, self.h.max())

    def _pressure(self, z: np.ndarray, p0: float) -> np.ndarray:
        return p0 + self.fft.backward(self.stiffness * self.fft.forward(z))

    def solve(self, p0: float, *, tol: float, max_iter: int) -> StanleyKatoStep:
        """Relax the displacement under mean pressure ``p0`` from the last state (warm start)."""
        if not (math.isfinite(p0) and p0 > 0) or not 0 < tol < 1 or max_iter < 1:
            raise ValueError(f"need p0 > 0, 0 < tol < 1 and max_iter >= 1, got {p0!r}, {tol!r}, {max_iter!r}")
        t0, z, h = time.perf_counter(), self.z, self.h
        quiet, it, load_error = 0, 0, math.inf
        while it < max_iter:
            p = self._pressure(z, p0)
            z_new = np.maximum(z - self.step_size * p, h)
            it += 1
            if it % CHECK_EVERY == 0:
                moved = float(np.abs(z_new - z).max()) / self.scale
                load_error = self._load_error(z_new, p0)
                quiet = quiet + 1 if (moved <= tol and load_error <= tol) else 0
            z = z_new
            if quiet >= 2:
                break
        self.z = z
        p = self._pressure(z, p0)
        contact = z <= h
        pressure = np.where(contact, np.maximum(p, 0.0), 0.0)
        return StanleyKatoStep(p0, pressure, z - h, float(contact.mean()),
                               abs(float(pressure.mean()) - p0) / p0, it, quiet >= 2,
                               time.perf_counter() - t0)

    def _load_error(self, z: np.ndarray, p0: float) -> float:
        p = self._pressure(z, p0)
        carried = float(np.where(z <= self.h, np.maximum(p, 0.0), 0.0).mean())
        return abs(carried - p0) / p0


def solve_stanley_kato(heights, pressures, *, e_star: float = 1.0, length: float = 1.0, tol: float = 1e-4,
                       max_iter: int = 20000, omega: float = OMEGA) -> list[StanleyKatoStep]:
    """Every load step of ``pressures`` (mean pressures, increasing) in turn, each warm-started.

    Returns one :class:`StanleyKatoStep` per load; ``heights`` ``(n, n)`` [length], ``e_star``
    [pressure], ``length`` the cell side [length], ``tol`` the stopping rule's tolerance.
    """
    sk = StanleyKato(heights, e_star=e_star, length=length, omega=omega)
    return [sk.solve(float(p0), tol=tol, max_iter=max_iter) for p0 in pressures]
