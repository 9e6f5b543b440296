"""The load steps a contact case receives: applied mean pressures p0 (:class:`LoadSchedule`).

The final load is given in one of three ways (a scene's ``contact.load``, ``config/README.md``):

- ``p_max`` with ``relative_to: e_star`` (generated scenes' default): ``p0 = p_max E*``, the
  same for every case;
- ``p_max`` with ``relative_to: rms_slope`` (measured scenes' default, ``p_max: 0.05``):
  ``p0 = p_max E* h'`` with ``h'`` the case's own rms slope, the paper's normalised pressure
  ``pbar``, so that a rough and a smooth file both reach the paper's regime (about 10 % contact
  at 0.05);
- ``target_area``: the final ``p0`` is the one whose contact area fraction is ``target_area``,
  found on the case's own surface by :func:`pressure_for_area` before the load steps run.

The load schedule (``uniform`` or ``geometric``) then runs from zero (or ``p_min``, on the same
scale as ``p_max``) to that final load: :func:`schedule`. :class:`LoadSchedule` holds a case's
schedule and resolves its pressures; it is the only schedule the package runs (the contact rule,
the accuracy study and the κ-gap study alike).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

#: A/A0 ~ kappa p0 / (E* h') at small loads (kappa about 2 on the paper's surfaces): the first
#: guess of :func:`pressure_for_area`, refined by the solver itself.
KAPPA_GUESS = 2.0
#: Relative tolerance on the target area fraction (a grid of n nodes cannot do better than 1/n).
AREA_RTOL = 0.01
#: Solves :func:`pressure_for_area` may spend before it stops and says how close it came.
MAX_PROBES = 12


def schedule(p_max: float, n_steps: int, kind: str = "uniform", p_min: float | None = None) -> list[float]:
    """``n_steps`` increasing loads ending at ``p_max`` [pressure].

    ``uniform`` (the paper's): ``p_max k / n`` for k = 1..n. ``geometric``: equal ratios
    from ``p_min`` (default ``p_max / n``, the uniform schedule's first step) to ``p_max``;
    it puts more steps at small A/A0, where the CEL's mu and beta are read off dp_bar/dp0.
    """
    if kind == "uniform":
        return [p_max * (i + 1) / n_steps for i in range(n_steps)]
    p_min = p_max / n_steps if p_min is None else p_min
    steps = [p_min * (p_max / p_min) ** (i / (n_steps - 1)) for i in range(n_steps)]
    steps[-1] = p_max  # exact end point
    return steps


@dataclass(frozen=True)
class LoadSchedule:
    """The load steps of a contact case: the one implementation of every schedule the package runs.

    A scene's ``load`` block (the pipeline's ``load_schedule``), the accuracy study's uniform steps and the
    κ-gap study's geometric ones (:mod:`roughcontact.studies`) are all this. Pressures are resolved per
    case, because ``relative_to: rms_slope`` scales with the case's own rms slope and
    ``target_area`` searches the case's own surface (:meth:`resolve`).

    Attributes
    ----------
    n_steps : int
        Number of load steps, >= 1.
    kind : {"uniform", "geometric"}
        :func:`schedule`'s kind.
    p_max, p_min : float or None
        Final (and, geometric, first) load on the scale of ``relative_to`` [1]; ``p_max`` is None
        with ``target_area``.
    relative_to : {"e_star", "rms_slope"}
        ``p0 = p_max E*`` or ``p0 = p_max E* h'`` (module docstring).
    target_area : float or None
        The final load is the one whose A/A0 is this (:func:`pressure_for_area`).

    Examples
    --------
    >>> LoadSchedule(4, p_max=0.005).pressures(e_star=2.0)
    [0.0025, 0.005, 0.0075, 0.01]
    """

    n_steps: int
    kind: str = "uniform"
    p_max: float | None = None
    p_min: float | None = None
    relative_to: str = "e_star"
    target_area: float | None = None

    def scale(self, e_star: float, rms_slope: float | None = None) -> float:
        """What ``p_max`` and ``p_min`` are in units of [pressure]: ``E*`` or ``E* h'``.

        ``rms_slope`` (h', the case's surface) is needed for ``relative_to: rms_slope``.
        """
        if self.relative_to == "e_star":
            return e_star
        if rms_slope is None or not (math.isfinite(rms_slope) and rms_slope > 0):
            raise ValueError(f"load.relative_to: rms_slope needs the surface's rms slope, a finite number > 0, "
                             f"got {rms_slope!r}")
        return e_star * rms_slope

    def pressures(self, e_star: float, rms_slope: float | None = None, p_final: float | None = None) -> list[float]:
        """Applied mean pressures p0 [pressure, E*'s unit], increasing, ``n_steps`` of them.

        ``p_final`` (from :func:`pressure_for_area`) replaces ``p_max`` for a ``target_area`` schedule;
        ``rms_slope`` is the case's h' for ``relative_to: rms_slope``.
        """
        if self.target_area is not None and p_final is None:
            raise ValueError("load.target_area: find the final load first (pressure_for_area) and pass it as p_final")
        p_max = p_final if p_final is not None else self.p_max * self.scale(e_star, rms_slope)
        p_min = self.p_min * self.scale(e_star, rms_slope) if self.p_min is not None else None
        return schedule(p_max, self.n_steps, self.kind, p_min)

    def resolve(self, e_star: float, rms_slope: float, n_nodes: int, area_at: Callable[[float], float] | None,
                log=None, name: str | None = None, cap: float | None = None) -> tuple[list[float], dict]:
        """The load steps of one case and what to record of them: ``(loads, attrs)``.

        ``area_at(p0)`` solves the case's surface at one load and returns its A/A0, used only with
        ``target_area`` (:func:`pressure_for_area`). ``name`` (the case's) starts the warning of a
        target A/A0 that no probe met: jobs run side by side and their lines meet in one console. ``cap``
        [pressure] (the settings' pressure cap, :attr:`roughcontact.solver.SolverSettings.hardness`): a
        ``target_area`` search stays under it (a final ``p_max`` the effects cannot carry: :meth:`check_final_load`).
        ``attrs`` (netCDF global attributes): ``load_relative_to`` and ``load_p_max`` as the scene gave
        them, or ``load_target_area``, ``load_target_area_reached`` (the probe's A/A0) and
        ``load_probes``; always ``load_p0_max``, the final p0 [pressure], and ``load_pbar_max`` =
        p0 / (E* h') of the last step.
        """
        if self.target_area is not None:
            loads, attrs = self._target_loads(e_star, rms_slope, n_nodes, area_at, log, name, cap)
        else:
            loads = self.pressures(e_star, rms_slope)
            attrs = {"load_relative_to": self.relative_to, "load_p_max": float(self.p_max)}
        attrs.update(load_p0_max=float(loads[-1]), load_pbar_max=float(loads[-1] / (e_star * rms_slope)))
        if log is not None:
            log.info("loads: p0 from %.6g to %.6g (p0/E* up to %.4g, p0/(E* h') up to %.4g) in %d steps", loads[0],
                     loads[-1], loads[-1] / e_star, attrs["load_pbar_max"], len(loads))
        return loads, attrs

    def _target_loads(self, e_star, rms_slope, n_nodes, area_at, log, name, cap) -> tuple[list[float], dict]:
        """The steps up to the load whose A/A0 is ``target_area``, found by probing the surface."""
        found = pressure_for_area(area_at, self.target_area, e_star=e_star, rms_slope=rms_slope, n_nodes=n_nodes,
                                  p_cap=cap)
        if log is not None:
            log.log(20 if found["reached"] else 30, "%starget A/A0 = %g: p0 = %.6g gives A/A0 = %.6g after %d solves%s",
                    f"{name}: " if name else "", self.target_area, found["pressure"], found["area"], found["probes"],
                    "" if found["reached"] else " (not within tolerance: the closest is used)")
        loads = self.pressures(e_star, rms_slope, p_final=found["pressure"])
        return loads, {"load_target_area": float(self.target_area), "load_target_area_reached": found["area"],
                       "load_probes": int(found["probes"])}

    def check_final_load(self, effects: Sequence, e_star: float, rms_slope: float | None, fail=None) -> None:
        """Refuse, before any solve, a final load one of ``effects`` cannot carry: each effect's own rule
        (:meth:`roughcontact.solver.effects.Effect.check_final_load`, e.g. a hardness above the load).

        ``fail(effect_name, field, message)`` reports one (default: a ``ValueError`` naming ``<name><field>``
        over E*). Nothing to check with ``target_area``: its search stays below a pressure cap (:meth:`resolve`).
        """
        if not effects or self.target_area is not None:
            return
        p_last = self.pressures(e_star, rms_slope)[-1]
        slope = "unknown" if rms_slope is None else f"{rms_slope:.6g}"
        load = (f"this case's final load p0/E* = {p_last / e_star:.6g} (load.p_max {self.p_max:g} relative to "
                f"{self.relative_to}, rms slope {slope})")
        for effect in effects:
            effect.check_final_load(p_last, e_star, load, functools.partial(fail or _refuse, effect.name))


def _refuse(name: str, field: str, message: str) -> None:
    raise ValueError(f"{name}{field}/E*: {message}")


def pressure_for_area(area_at: Callable[[float], float], target: float, *, e_star: float, rms_slope: float,
                      n_nodes: int, rtol: float = AREA_RTOL, max_probes: int = MAX_PROBES,
                      p_cap: float | None = None) -> dict:
    """The applied mean pressure p0 [pressure] at which the contact area fraction is ``target``.

    ``area_at(p0)`` solves the case at one load and returns A/A0 [1] (it grows with p0). The
    search starts at ``p0 = target E* h' / KAPPA_GUESS`` and steps in log-log (secant on
    ``ln A`` against ``ln p0``, the slope kept in [0.2, 5]), keeping a bracket once it has one.
    It stops when ``|A - target| <= max(rtol target, 1.5 / n_nodes)`` (a grid's area moves in
    steps of 1 / n_nodes) or after ``max_probes`` solves.

    ``p_cap`` (a hardness times E*): every probe stays below it, where a capped solve can carry the load
    (a probe that would reach it goes halfway from the highest load below the target to the cap; with a
    cap the area reaches 1 as p0 reaches it, so a target area always has its load below the cap).

    Returns ``{"pressure", "area", "probes", "reached"}``: the best p0 found, its A/A0, the
    number of solves and whether the tolerance was met.
    """
    if not 0 < target < 1:
        raise ValueError(f"target_area must lie in (0, 1), got {target!r}")
    tol = max(rtol * target, 1.5 / n_nodes)
    p = _below_cap(target * e_star * rms_slope / KAPPA_GUESS, 0.0, p_cap)
    below, above, last, best = None, None, None, None
    for probe in range(1, max_probes + 1):
        area = float(area_at(p))
        if best is None or abs(area - target) < abs(best[1] - target):
            best = (p, area)
        if abs(area - target) <= tol:
            return {"pressure": p, "area": area, "probes": probe, "reached": True}
        if area < target:
            below = (p, area) if below is None or p > below[0] else below
        else:
            above = (p, area) if above is None or p < above[0] else above
        p_next = _next_pressure(p, area, target, last)
        if below and above and not below[0] < p_next < above[0]:
            p_next = math.sqrt(below[0] * above[0])  # the secant left the bracket: bisect in log
        last, p = (p, area), _below_cap(p_next, below[0] if below else 0.0, p_cap)
    return {"pressure": best[0], "area": best[1], "probes": max_probes, "reached": False}


def _below_cap(p: float, low: float, p_cap: float | None) -> float:
    """``p``, or halfway from ``low`` (a load known to be below the target) to the cap when ``p`` reaches it."""
    return p if p_cap is None or p < p_cap else 0.5 * (low + p_cap)


def _next_pressure(p: float, area: float, target: float, last: tuple[float, float] | None) -> float:
    """One log-log secant step towards ``target`` from ``(p, area)`` (slope 1 without a previous probe)."""
    slope = 1.0
    if last is not None and last[0] != p and last[1] > 0 and area > 0 and last[1] != area:
        slope = min(5.0, max(0.2, math.log(area / last[1]) / math.log(p / last[0])))
    if area <= 0:
        return 10.0 * p
    return p * (target / area) ** (1.0 / slope)
