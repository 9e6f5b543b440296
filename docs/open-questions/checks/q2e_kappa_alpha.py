"""Independent check of Q2e: where κ's fall in ln α bends, and which α is plotted (issue 61).

Reads the paper grid's λ_s = 32 Δx column (docs/reproduction/paper-grid/data/contact.nc, k_s = 32,
N = 1024), kappa-alpha.nc (k_s = 64, N = 2048) and kappa-alpha-4096.nc (k_s = 128, N = 4096): every
point at 32 pixels per λ_s. Per (k_l, H): κ(0.05)/√2π of each seed (linear in ln A between the steps),
its seed mean and standard error, and the seed mean of the surfaces' measured α. Weighted fits in ln α
over all points and over subsets, with the pixel-counted and the perimeter-corrected area, and with
three α's: measured (the page's), the expected lattice spectrum's and the continuum closed form's.

Run: ``python docs/open-questions/checks/q2e_kappa_alpha.py``; its output is q2e_kappa_alpha.txt.
"""

from __future__ import annotations

import numpy as np
from common import DATA, REPRODUCTION, SQRT_2PI, kappa_at, load, mean_sem, wls

SPLIT = 3.0
SOURCES = ((REPRODUCTION / "paper-grid" / "data" / "contact.nc", 32.0), (DATA / "kappa-alpha.nc", 64.0),
           (DATA / "kappa-alpha-4096.nc", 128.0))


def lattice_alpha(k_l: float, k_s: float, hurst: float) -> float:
    """Nayak's α of the power law ``|k|^(-2(1+H))`` summed over the integer modes with ``k_l <= |k| <= k_s``.

    Profile moments of the isotropic field, averaged over x and y: ``m0 = Σ c``, ``m2 = Σ (kx² + ky²) c / 2``,
    ``m4 = Σ (kx⁴ + ky⁴) c / 2`` (the 2π factors cancel in α). k_s < N/2 here: no Nyquist mode.
    """
    r = int(np.ceil(k_s))
    kx, ky = np.meshgrid(np.arange(-r, r + 1.0), np.arange(-r, r + 1.0), indexing="ij")
    k2 = kx**2 + ky**2
    band = (k2 >= k_l**2) & (k2 <= k_s**2)
    c = np.where(band, np.where(k2 > 0, k2, 1.0) ** -(1.0 + hurst), 0.0)
    m0, m2, m4 = c.sum(), 0.5 * (k2 * c).sum(), 0.5 * ((kx**4 + ky**4) * c).sum()
    return float(m0 * m4 / m2**2)


def closed_form_alpha(k_l: float, k_s: float, hurst: float) -> float:
    """Nayak's α of the continuous power law on the annulus: (3/2) I(−1−2H) I(3−2H) / I(1−2H)², I(p) = ∫ k^p dk.

    The isotropic profile moments carry the angular means of cos² (1/2) and cos⁴ (3/8): 3/8 / (1/2)² = 3/2.
    """
    def integral(p):
        return np.log(k_s / k_l) if abs(p + 1) < 1e-12 else (k_s ** (p + 1) - k_l ** (p + 1)) / (p + 1)

    h = hurst
    return float(1.5 * integral(-1 - 2 * h) * integral(3 - 2 * h) / integral(1 - 2 * h) ** 2)


def points(corrected: bool = False) -> dict[str, np.ndarray]:
    """One row per (k_l, k_s, H): α's, κ(0.05)/√2π seed mean and standard error, N, per-seed α."""
    out = {k: [] for k in ("alpha", "lattice", "closed", "kappa", "sem", "k_l", "k_s", "H", "N", "alphas")}
    for path, k_s in SOURCES:
        ds = load(path).sel(k_s=k_s)
        for k_l in ds["k_l"].values:
            for h in ds["H"].values:
                case = ds.sel(k_l=k_l, H=h)
                area, kap = case["area_fraction"].values, case["kappa"].values
                if corrected:
                    kap = kap * case["area_fraction_corrected"].values / area
                    area = case["area_fraction_corrected"].values
                per_seed = [kappa_at(area[i], kap[i], 0.05) / SQRT_2PI for i in range(area.shape[0])]
                m, s, n = mean_sem(per_seed)
                if not (np.isfinite(m) and np.isfinite(s)):
                    continue
                alphas = case["alpha"].values
                for key, value in (("alpha", np.nanmean(alphas)), ("lattice", lattice_alpha(k_l, k_s, h)),
                                   ("closed", closed_form_alpha(k_l, k_s, h)), ("kappa", m), ("sem", s),
                                   ("k_l", k_l), ("k_s", k_s), ("H", h), ("N", int(ds.attrs["n"])),
                                   ("alphas", tuple(alphas))):
                    out[key].append(value)
    return {k: (np.array(v) if k != "alphas" else v) for k, v in out.items()}


def fits(p: dict, alpha: np.ndarray, sel: np.ndarray) -> dict:
    """Slope (linear fit) and curvature ((ln α)² coefficient of the quadratic fit) over ``sel``, with errors."""
    x, y, e = np.log(alpha[sel]), p["kappa"][sel], p["sem"][sel]
    lin, lcov, chi2 = wls(x, y, e, 1)
    quad, qcov, _ = wls(x, y, e, 2)
    return {"n": int(sel.sum()), "slope": lin[1], "slope_se": np.sqrt(lcov[1, 1]), "curv": quad[2],
            "curv_se": np.sqrt(qcov[2, 2]), "line": lin, "line_cov": lcov, "chi2": chi2}


def at_top(p: dict, alpha: np.ndarray, fit: dict) -> tuple[float, float, float, float, float]:
    """A line fit at the largest α: (α, line, its se, measured, z with the point's error scaled as the fit's)."""
    top = int(np.argmax(alpha))
    v = np.array([1.0, np.log(alpha[top])])
    line, se = float(v @ fit["line"]), float(np.sqrt(v @ fit["line_cov"] @ v))
    z = (p["kappa"][top] - line) / np.sqrt(p["sem"][top] ** 2 * max(fit["chi2"], 1.0) + se**2)
    return float(alpha[top]), line, se, float(p["kappa"][top]), float(z)


def results() -> dict:
    out = {}
    for area in ("pixel-counted", "perimeter-corrected"):
        p = points(area == "perimeter-corrected")
        for which in ("alpha", "lattice", "closed"):
            a = p[which]
            subsets = {"all": np.ones(a.size, bool), f"α < {SPLIT:g}": a < SPLIT, f"α ≥ {SPLIT:g}": a >= SPLIT,
                       "α ≥ 5": a >= 5, "N = 4096 only": p["N"] == 4096}
            out[area, which] = {name: fits(p, a, sel) for name, sel in subsets.items()}
            out[area, which]["top above"] = at_top(p, a, out[area, which][f"α ≥ {SPLIT:g}"])
            out[area, which]["top all"] = at_top(p, a, out[area, which]["all"])
        out[area, "points"] = p
    return out


def main() -> None:
    r = results()
    p = r["pixel-counted", "points"]
    top = int(np.argmax(p["alpha"]))
    print("Q2e check (docs/open-questions/checks/q2e_kappa_alpha.py): every point at 32 px per λ_s")
    print(f"points: {p['alpha'].size}; measured α from {p['alpha'].min():.3g} to {p['alpha'].max():.4g}")
    print(f"largest α: N = {p['N'][top]}, k_l = {p['k_l'][top]:g}, k_s = {p['k_s'][top]:g}, H = {p['H'][top]:g}: "
          f"per-seed measured α {', '.join(f'{v:.1f}' for v in p['alphas'][top])}, their mean {p['alpha'][top]:.1f}; "
          f"expected lattice spectrum {p['lattice'][top]:.1f}; continuum closed form {p['closed'][top]:.1f}")
    for name, sel in (("λ_l = L, L/2 (k_l ≤ 2)", p["k_l"] <= 2), ("λ_l ≤ L/4 (k_l ≥ 4)", p["k_l"] >= 4)):
        for which in ("lattice", "closed"):
            ratio = p[which][sel] / p["alpha"][sel]
            print(f"{which} α / measured α at {name}: {ratio.min():.3f} to {ratio.max():.3f}")
    gap = np.sort(p["alpha"])
    i = int(np.searchsorted(gap, SPLIT))
    print(f"no point between α = {gap[i - 1]:.2f} and {gap[i]:.2f}; below α = {SPLIT:g}: k_l = "
          f"{', '.join(f'{v:g}' for v in np.unique(p['k_l'][p['alpha'] < SPLIT]))} at N = "
          f"{', '.join(str(v) for v in np.unique(p['N'][p['alpha'] < SPLIT]))}")
    for (area, which), fs in r.items():
        if which == "points":
            continue
        print(f"{area}, {dict(alpha='measured α', lattice='expected lattice α', closed='closed-form α')[which]}:")
        for name, f in fs.items():
            if name.startswith("top"):
                continue
            print(f"  {name} ({f['n']} points): slope {f['slope']:+.4f} ± {f['slope_se']:.4f}, curvature "
                  f"{f['curv']:+.4f} ± {f['curv_se']:.4f} ({f['curv'] / f['curv_se']:+.1f} se), reduced χ² "
                  f"{f['chi2']:.2f}")
        for name in ("top above", "top all"):
            a, line, se, k, z = fs[name]
            print(f"  the {'α ≥ 3' if name == 'top above' else 'all-points'} line at α = {a:.4g}: {line:.3f} ± "
                  f"{se:.3f}; measured {k:.3f}; z = {z:+.2f}")


if __name__ == "__main__":
    main()
