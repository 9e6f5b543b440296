"""Every registered figure (roughcontact.figures.registry.FIGURES) drawn from small made-up data, by name.

:func:`builders` gives one function per registered figure that draws it with the function its registry entry
renders with; a test over every registered figure (tests/test_figures.py) checks that the names match, so a new
figure needs a builder here before the suite passes. :func:`labelled_ticks` reads the tick labels an axis shows.
"""
from functools import cache

import numpy as np
import xarray as xr

from cel_synthetic import simulate_cel_cases
from roughcontact.analysis.aggregate.combine import CASE_DIMS, combine_cases
from roughcontact.analysis.aggregate.derived import aggregate_contact
from roughcontact.analysis.aggregate.seeds import representativity_statistics, seed_statistics
from roughcontact.analysis.fit.grid import fit_cel
from roughcontact.figures import measured
from roughcontact.figures.accuracy import fig_accuracy
from roughcontact.figures.adhesion import fig_hysteresis, fig_pull_off
from roughcontact.figures.area_load import fig_area_load
from roughcontact.figures.contact_map import fig_contact_maps
from roughcontact.figures.dpbar import fig_dpbar
from roughcontact.figures.kappa import fig_kappa
from roughcontact.figures.representativity import fig_representativity, fig_surface_examples
from roughcontact.pipeline.datasets import contact_dataset, surface_dataset
from roughcontact.solver import solve_contact
from roughcontact.solver.adhesion import PULL_OFF_STATUS
from roughcontact.surfaces.synthetic import generate_surface, spectral_moments


@cache
def contact():
    """A synthetic CEL aggregate (2 k_l x 2 k_s x 2 H x 3 seeds), its seed statistics and fit."""
    dss, names = simulate_cel_cases(k_l=(4.0, 16.0), k_s=(32.0, 128.0), hurst=(0.36, 0.84), seeds=range(3),
                                    point_noise=1e-4, seed_scatter=0.01, rng_seed=5)
    agg = aggregate_contact(dss, names)
    return agg, seed_statistics(agg), fit_cel(agg, n_boot=10)


def rep_stats(eps=lambda kl, ks: 0.3 / kl * (32 / ks) ** 0.3, k_l=(1.0, 4.0, 16.0), k_s=(32.0, 64.0, 128.0),
              std=0.1, seed=0):
    """A representativity aggregate as the workflow writes it (per-case epsilon and std_height, and their seed
    statistics), eps ``eps(k_l, k_s)`` with 10 % scatter over 3 seeds."""
    dss, names = [], []
    rng = np.random.default_rng(seed)
    for kl in k_l:
        for ks in k_s:
            for s in range(3):
                e = eps(kl, ks) * (1 + 0.1 * rng.standard_normal())
                dss.append(xr.Dataset(
                    {"epsilon": (CASE_DIMS, np.full((1, 1, 1, 1), e), {"units": "1/L", "long_name": "L2 error"}),
                     "std_height": (CASE_DIMS, np.full((1, 1, 1, 1), std), {"units": "L"})},
                    coords={"k_l": [kl], "k_s": [ks], "H": [0.8], "seed": np.array([s], dtype=np.int64)}))
                names.append(f"kl{kl:g}_ks{ks:g}_s{s}.nc")
    cases = combine_cases(dss, names, kind="representativity")
    return cases.merge(representativity_statistics(cases))


def map_case(k_l: str, n: int = 32) -> tuple[xr.Dataset, xr.Dataset]:
    """A generated 2-D case with fields stored at steps 2 and 4: its surface file's and contact file's datasets."""
    h = generate_surface(n, int(k_l), 8, 0.5, seed=0, rms_slope=0.1)
    res = solve_contact(h, [0.005 * (i + 1) / 4 for i in range(4)], store_fields=[2, 4], length_unit="um")
    surface = surface_dataset(h, k_l=k_l, k_s="8", hurst="0.5", seed=0, length=1.0,
                              normalisation={"rms_slope": 0.1}, length_unit="um")
    return surface, contact_dataset(res, rms_slope=0.1, alpha=2.0, e_star=1.0, k_l=k_l, k_s="8", hurst="0.5", seed=0)


def adhesive_case(scale: float) -> xr.Dataset:
    """A made-up adhesive case: a loading branch of 5 steps and an unloading branch of 6, its pull-off."""
    gap = np.linspace(1.0, 0.2, 5)
    unload_gap = np.linspace(0.2, 1.2, 6)
    unload_p = scale * np.array([4.0, 2.0, 0.5, -0.6, -0.3, 0.0])
    return xr.Dataset({
        "pressure": ("step", scale * np.linspace(0.5, 4.0, 5)), "area_fraction": ("step", np.linspace(0.01, 0.2, 5)),
        "mean_gap": ("step", gap, {"units": "um"}), "converged": ("step", np.ones(5, bool)),
        "unload_mean_gap": ("unload_step", unload_gap), "unload_mean_pressure": ("unload_step", unload_p),
        "unload_area_fraction": ("unload_step", np.linspace(0.2, 0.0, 6)),
        "unload_converged": ("unload_step", np.ones(6, bool)), "pull_off_pressure": ((), 0.6 * scale),
    }, attrs={"e_star": 1.0})


def pull_off_aggregate(case_dims=("k_l", "k_s", "H", "seed")) -> xr.Dataset:
    """A made-up pull-off aggregate of 4 cases (2 groups of 2 seeds, or 4 topographies), one untrusted."""
    shape = (1, 1, 2, 2) if len(case_dims) == 4 else (4,)
    flags = {"flag_values": np.arange(len(PULL_OFF_STATUS), dtype=np.int8), "flag_meanings": " ".join(PULL_OFF_STATUS)}
    coords = ({"k_l": [4.0], "k_s": [32.0], "H": [0.36, 0.84], "seed": [0, 1]} if len(case_dims) == 4
              else {"topography": np.array(["a", "b", "c", "d"], dtype=object)})
    return xr.Dataset({
        "pull_off_pressure": (case_dims, np.array([1e-4, 3e-4, 2e-4, np.nan]).reshape(shape), {"units": "1"}),
        "pull_off_status": (case_dims, np.array([0, 0, 0, 1], dtype=np.int8).reshape(shape), {"units": "1", **flags}),
    }, coords=coords, attrs={"e_star": 2.0})


def topography(name: str, seed: int, n: int = 64) -> xr.Dataset:
    """A measured surface file's dataset (an ``n x n`` map in um)."""
    length = 100.0
    heights = generate_surface(n, 4, 32, 0.8, seed, rms_height=1.5, length=length)
    stats = spectral_moments(heights, length)
    x = np.arange(n) * length / n

    def scalar(key, units):
        return ("topography", [stats[key]], {"units": units})

    return xr.Dataset(
        {"heights": (("x", "y"), heights, {"units": "um"}), "rms_height": scalar("rms_height", "um"),
         "rms_slope": scalar("rms_slope", "1"), "alpha": scalar("alpha", "1")},
        coords={"x": ("x", x, {"units": "um"}), "y": ("y", x.copy(), {"units": "um"}),
                "topography": ("topography", np.array([name], dtype=object))},
        attrs={"length": length, "n": n, "length_units": "um"})


@cache
def measured_contact():
    """A measured scene's contact aggregate (3 topographies) and its pooled fit."""
    from roughcontact.analysis.fit import fit_topographies

    dss, names = simulate_cel_cases(seeds=range(3), point_noise=1e-3, seed_scatter=0.0, area_max=0.13, rng_seed=3)
    agg = aggregate_contact(dss, names).isel(k_l=0, k_s=0, H=0, drop=True).rename(seed="topography")
    agg = agg.assign_coords(topography=np.array(["a", "b", "c"], dtype=object))
    return agg, fit_topographies(agg, n_boot=10)


def builders() -> dict:
    """One function per registered figure name, drawing it from made-up data."""
    def grid(draw):
        return lambda: draw(*contact())

    def patches(draw):
        return lambda: draw(*measured_contact(), sizes={"a": (64, 64), "b": (64, 64), "c": (64, 64)})

    maps = lambda: fig_contact_maps([map_case("2"), map_case("4")])  # noqa: E731
    cycles = lambda: fig_hysteresis([("a", adhesive_case(1e-3)), ("b", adhesive_case(2e-3))])  # noqa: E731
    return {
        "representativity": lambda: fig_representativity(rep_stats()),
        "surface_examples": lambda: fig_surface_examples(
            [(generate_surface(64, kl, 32, 0.8, 0, rms_height=0.1), f"$k_l = {kl}$") for kl in (1, 4, 16)]),
        "area_load": grid(fig_area_load), "kappa": grid(fig_kappa), "dpbar": grid(fig_dpbar),
        "hysteresis": cycles,
        "pull_off": lambda: fig_pull_off(pull_off_aggregate(), ("k_l", "k_s", "H", "seed")),
        "contact_map": maps,
        "accuracy": lambda: fig_accuracy(accuracy_summary()),
        "topographies": lambda: measured.fig_topographies([topography("a", 0), topography("b", 1)]),
        "measured_area_load": patches(measured.fig_measured_area_load),
        "measured_kappa": patches(measured.fig_measured_kappa),
        "measured_contact_map": maps,
        "measured_hysteresis": cycles,
        "measured_pull_off": lambda: fig_pull_off(pull_off_aggregate(("topography",)), ("topography",)),
    }


def accuracy_summary() -> xr.Dataset:
    """A made-up accuracy summary: two settings per axis and the defaults."""
    axis = ["N", "N", "tol", "tol", "seeds", "seeds", "defaults"]
    err = [0.03, 0.01, 0.0, 0.002, 0.02, 0.03, 0.01]
    value = ["256", "512", "1e-10", "1e-8", "2", "4", "-"]
    return xr.Dataset({"axis": ("variant", axis), "value": ("variant", value),
                       "work_per_case": ("variant", [1.0, 4.0, 3.0, 2.0, 2.0, 4.0, 2.0]),
                       **{f"err_{m}": ("variant", err)
                          for m in ("kappa", "area", "kappa_corrected", "area_corrected")}},
                      attrs={"kappa_at": 0.05})


def labelled_ticks(axis) -> list[str]:
    """The tick labels an axis shows at its limits (major and minor, non-empty), from its locators and formatters
    as drawn."""
    lo, hi = sorted(axis.get_view_interval())
    out = []
    for locator, formatter in ((axis.get_major_locator(), axis.get_major_formatter()),
                               (axis.get_minor_locator(), axis.get_minor_formatter())):
        locs = [v for v in locator() if lo - 1e-12 * abs(lo) <= v <= hi + 1e-12 * abs(hi)]
        out += [t for t in formatter.format_ticks(locs) if t.strip()]
    return out
