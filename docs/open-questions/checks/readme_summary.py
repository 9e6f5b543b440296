"""Independent check of the README's summary line of the open-questions page (issue 61).

Recomputes every number the line quotes from the published files: Q1a (the CEL's 5 % and 4 %
crossings, from full-contact.nc and its fit full-contact-cel.nc), Q1c (full contact at each surface's
exact load), Q2e, Q3a (κ on L and 2L cells: docs/reproduction/data/contact.nc and
representative-2L.nc), Q4a and Q4d (the other checks of this folder).

Run: ``python docs/open-questions/checks/readme_summary.py``; its output is readme_summary.txt.
"""

from __future__ import annotations

import numpy as np
import q2e_kappa_alpha
import q4a_mean_gap
import q4d_percolation
from common import DATA, REPRODUCTION, SQRT_2PI, kappa_at, load, mean_sem, one_cell


def cel() -> dict:
    """Q1a: the pooled mean A/A0 against the CEL A = x (1 + β x^(1−μ))^(−1/(1−μ)), x = κ p̄."""
    ds = one_cell(load(DATA / "full-contact.nc"))
    fit = load(DATA / "full-contact-cel.nc")["value"].isel(k_l=0, k_s=0)
    const = {c: float(fit.sel(H_group="pooled", estimator="paper", constant=c)) for c in ("kappa", "mu", "beta")}
    pbar = (ds["pressure"] / (float(ds.attrs["e_star"]) * ds["rms_slope"])).mean(("H", "seed")).values
    area = ds["area_fraction"].mean(("H", "seed")).values
    x = const["kappa"] * pbar
    dev = np.abs(x * (1 + const["beta"] * x ** (1 - const["mu"])) ** (-1 / (1 - const["mu"])) / area - 1)
    out = {"constants": const}
    for tol in (0.05, 0.04):
        k = int(np.argmax(dev > tol))
        out[tol] = (area[k - 1] + (tol - dev[k - 1]) / (dev[k] - dev[k - 1]) * (area[k] - area[k - 1]),
                    area[k - 1], area[k])
    return out


def onset() -> tuple[int, int]:
    """Q1c: cases whose steps are in full contact exactly above the exact full-contact load."""
    ds = one_cell(load(DATA / "full-contact.nc"))
    full = ds["area_fraction"].values >= 1.0
    above = ds["pressure"].values > ds["full_contact_pressure"].values[..., None]
    same = (full == above).all(axis=-1)
    return int(same.sum()), int(same.size)


def cells() -> list[tuple[float, float, float]]:
    """Q3a: (H, A/A0, z) of κ on the 2L cell against the L cell, z over both standard errors."""
    small = load(REPRODUCTION / "data" / "contact.nc").sel(k_l=16.0, k_s=32.0)
    large = one_cell(load(DATA / "representative-2L.nc"))
    out = []
    for h in large["H"].values:
        for target in (0.01, 0.05, 0.1):
            stats = []
            for ds in (small.sel(H=h), large.sel(H=h)):
                a, k = ds["area_fraction"].values, ds["kappa"].values
                stats.append(mean_sem([kappa_at(a[i], k[i], target) / SQRT_2PI for i in range(a.shape[0])]))
            (m1, s1, _), (m2, s2, _) = stats
            out.append((float(h), target, (m2 - m1) / np.hypot(s1, s2)))
    return out


def main() -> None:
    print("README summary check (docs/open-questions/checks/readme_summary.py)")
    c = cel()
    for tol in (0.05, 0.04):
        at, lo, hi = c[tol]
        print(f"Q1a: the CEL leaves {100 * tol:.0f} % at A/A0 = {at:.3f} (between the steps at {lo:.3f} and {hi:.3f})")
    k, n = onset()
    print(f"Q1c: full contact exactly above each surface's exact load in {k} of {n} cases")
    q2 = q2e_kappa_alpha.results()
    main_fit = q2["pixel-counted", "alpha"]
    p = q2["pixel-counted", "points"]
    top = int(np.argmax(p["alpha"]))
    below, above = main_fit["α < 3"], main_fit["α ≥ 3"]
    corrected = q2["perimeter-corrected", "alpha"]["α ≥ 3"]
    print(f"Q2e: κ/√2π per e-fold of α: {below['slope']:+.3f} ± {below['slope_se']:.3f} below α = 3, "
          f"{above['slope']:+.4f} ± {above['slope_se']:.4f} above it (curvature above: "
          f"{above['curv'] / above['curv_se']:+.1f} se pixel-counted, {corrected['curv'] / corrected['curv_se']:+.1f} "
          f"se perimeter-corrected); κ/√2π = {p['kappa'][top]:.3f} at α = {p['alpha'][top]:.0f}")
    zs = [z for _, _, z in cells()]
    print(f"Q3a: κ on 2L against L cells: |z| ≤ {max(abs(z) for z in zs):.2f} at {len(zs)} points")
    q4 = q4a_mean_gap.results()
    def gap_ratios(name):  # the main line's: midpoint w(q), γ = 0.45
        return [v for k, v in q4[name]["ratios"].items() if k[2:] == ("gap", "midpoint", 0.45)]

    main_cell = gap_ratios("full-contact.nc")
    modes = gap_ratios("persson-modes-256.nc") + gap_ratios("persson-modes-512.nc")
    print(f"Q4a: mean gap / Persson's at γ = 0.45 (midpoint w(q), expected spectrum): {min(main_cell):.3f} to "
          f"{max(main_cell):.3f} on the page's surfaces (k_l = 16; A/A0 = 0.01, 0.1), {min(modes):.3f} to "
          f"{max(modes):.3f} on the k_l = 4 and 8 cells (A/A0 = 0.01)")
    d = q4d_percolation.results()["percolation.nc", 4]
    print(f"Q4d: one-direction threshold A/A0 = {d['one direction']:.3f} ± {d['u']:.3f} (Dapp et al.: 0.42)")


if __name__ == "__main__":
    main()
