"""Independent check of Q4a (and Q4b): Persson's mean gap and stiffness against the measured ones (issue 61).

Reads full-contact.nc (k_l = 16, k_s = 32, N = 1024, five H, 12 seeds) and the mode-count cells
persson-modes-256.nc (k_l = 4, k_s = 8) and persson-modes-512.nc (k_l = 8, k_s = 16). Persson's
mean separation (Persson 2007; Yang & Persson 2008) is written here from its formula:

    u(p0) = √π ∫ dq q² C(q) w(q) J(w(q) p0 / E*),   w(q) = (π ∫_q0^q q'³ C dq')^(−1/2),
    J(s0) = ∫_s0^∞ [γ + 3 (1 − γ) erf(s)²] exp(−s²) ds / s,

on the generator's expected spectrum: the integer modes (kx, ky) of the N × N grid with
k_l ≤ |k| ≤ k_s, power ∝ |k|^(−2(1+H)), 2π q C dq → c per mode, scaled to the surfaces' rms slope.
The modes come in shells of one |k|; where w is read inside a shell is the discretisation:
``midpoint`` (the page's main line: the power below the shell plus half its own), ``whole shell``
(all of its own), ``per mode`` (mode by mode in the grid's row-major order), and ``continuum``
(the integral over the ideal power law on [q_l, q_s], by adaptive quadrature). The stiffness is
K = −dp0/du = p0 / [(1/(2√π)) Σ q c w f(w p0/E*)], f(s) = [γ + 3(1 − γ) erf(s)²] exp(−s²).
The ratio measured/Persson is read where the seed-mean A/A0 crosses 0.01 and 0.1 (linear in A/A0
between the two steps).

Run: ``python docs/open-questions/checks/q4a_mean_gap.py``; its output is q4a_mean_gap.txt.
"""

from __future__ import annotations

import numpy as np
from common import DATA, crossing, load, one_cell
from scipy.integrate import cumulative_trapezoid, quad
from scipy.special import erf, exp1

GAMMAS = (0.4, 0.45, 0.5)
RULES = ("midpoint", "whole shell", "per mode", "continuum")

# H(s) = ∫_s^∞ erf(t)² exp(−t²) dt / t on a fine grid in ln t (trapezoid; the tail above t = 9 is < 1e-36).
_LOG_T = np.linspace(np.log(1e-9), np.log(9.0), 400001)
_T = np.exp(_LOG_T)
_H = cumulative_trapezoid((erf(_T) ** 2 * np.exp(-_T**2))[::-1], -_LOG_T[::-1], initial=0.0)[::-1]


def big_j(s: np.ndarray, gamma: float) -> np.ndarray:
    """J(s) = (γ/2) E1(s²) + 3 (1 − γ) H(s)."""
    s = np.asarray(s, float)
    h = np.interp(np.log(np.clip(s, _T[0], _T[-1])), _LOG_T, _H)
    return 0.5 * gamma * exp1(s * s) + 3.0 * (1.0 - gamma) * np.where(s >= _T[-1], 0.0, h)


def small_f(s: np.ndarray, gamma: float) -> np.ndarray:
    return (gamma + 3.0 * (1.0 - gamma) * erf(s) ** 2) * np.exp(-s * s)


def lattice(n: int, k_l: float, k_s: float, hurst: float, slope: float, length: float):
    """The band's modes in the grid's row-major order: (k², q, c), Σ q² c = slope²."""
    m = np.fft.fftfreq(n, 1.0 / n)
    kx, ky = np.meshgrid(m, m, indexing="ij")
    k2 = (kx**2 + ky**2).ravel()
    band = (k2 >= k_l**2) & (k2 <= k_s**2)
    k2 = k2[band]
    q = 2 * np.pi * np.sqrt(k2) / length
    c = k2 ** -(1.0 + hurst)
    return k2, q, c * slope**2 / np.sum(q * q * c)


def terms(k2, q, c, rule):
    """(a, w) of u = (1/(2√π)) Σ a J(w p0/E*) for a discretisation rule of a discrete spectrum."""
    if rule == "per mode":
        order = np.argsort(k2, kind="stable")
        w = (0.5 * np.cumsum((q * q * c)[order])) ** -0.5
        return (q * c)[order] * w, w
    shells, inverse = np.unique(k2, return_inverse=True)
    power = np.bincount(inverse, q * q * c)
    qc = np.bincount(inverse, q * c)
    below = np.cumsum(power) - (0.5 * power if rule == "midpoint" else 0.0)
    w = (0.5 * below) ** -0.5
    return qc * w, w


def discrete(p0, a, w, gamma, e_star):
    s = np.outer(p0, w) / e_star
    gap = big_j(s, gamma) @ a / (2 * np.sqrt(np.pi))
    stiffness = p0 / (small_f(s, gamma) @ a / (2 * np.sqrt(np.pi)))
    return gap, stiffness


def continuum(p0, k_l, k_s, hurst, slope, length, gamma, e_star):
    """Gap and stiffness of the continuous power law on [q_l, q_s], by adaptive quadrature in q."""
    ql, qs = 2 * np.pi * k_l / length, 2 * np.pi * k_s / length
    p = 2 - 2 * hurst

    def below(q):  # ∫_ql^q x³ x^(−2(1+H)) dx
        return np.log(q / ql) if abs(p) < 1e-12 else (q**p - ql**p) / p

    c0 = slope**2 / (2 * np.pi * below(qs))

    def w(q):
        return (np.pi * c0 * below(q)) ** -0.5

    gaps, ks = [], []
    for p0_ in np.atleast_1d(p0):
        def weight(q):
            return q * q * c0 * q ** (-2 * (1 + hurst)) * w(q)

        g = np.sqrt(np.pi) * quad(lambda q, p0_=p0_: weight(q) * big_j(w(q) * p0_ / e_star, gamma), ql, qs, limit=400,
                                  epsabs=0, epsrel=1e-9)[0]
        d = np.sqrt(np.pi) * quad(lambda q, p0_=p0_: weight(q) * small_f(w(q) * p0_ / e_star, gamma), ql, qs, limit=400,
                                  epsabs=0, epsrel=1e-9)[0]
        gaps.append(g)
        ks.append(p0_ / d)
    return np.array(gaps), np.array(ks)


def ratios(name: str, areas=(0.01, 0.1)) -> dict:
    """{(H, target, key, rule, γ): measured/Persson} and {(H, target, key): seed s.e. / mean} of one file."""
    ds = one_cell(load(DATA / name))
    n, length, e_star = int(ds.attrs["n"]), float(ds.attrs["length"]), float(ds.attrs["e_star"])
    k_l, k_s = float(ds["k_l"]), float(ds["k_s"])
    slope = float(ds["rms_slope"].mean())
    out, noise = {}, {}
    for h in ds["H"].values:
        sub = ds.sel(H=h)
        area = sub["area_fraction"].mean("seed").values
        p0 = sub["pressure"].mean("seed").values
        measured = {"gap": sub["mean_gap"], "stiffness": sub["contact_stiffness"]}
        k2, q, c = lattice(n, k_l, k_s, float(h), slope, length)
        for target in areas:
            kk = int(np.searchsorted(area, target))
            steps = [kk - 1, kk]  # Persson is needed at the two steps around the crossing only
            for key, da in measured.items():
                mean = da.mean("seed").values[steps]
                sem = da.std("seed", ddof=1).values[steps] / np.sqrt(da.sizes["seed"])
                noise[float(h), target, key] = crossing(area[steps], sem / mean, target)
            for rule in RULES:
                for g in GAMMAS if rule == "midpoint" else (0.45,):
                    if rule == "continuum":
                        theory = continuum(p0[steps], k_l, k_s, float(h), slope, length, g, e_star)
                    else:
                        theory = discrete(p0[steps], *terms(k2, q, c, rule), g, e_star)
                    for key, t in zip(("gap", "stiffness"), theory, strict=True):
                        r = measured[key].mean("seed").values[steps] / t
                        out[float(h), target, key, rule, g] = crossing(area[steps], r, target)
                        if rule == "midpoint" and g == 0.45:
                            out[float(h), target, key, "step to step"] = abs(r[1] - r[0])
    return {"ratios": out, "noise": noise, "k_l": k_l, "k_s": k_s, "n": n}


def results() -> dict:
    return {name: ratios(name, (0.01, 0.1) if name == "full-contact.nc" else (0.01,))
            for name in ("full-contact.nc", "persson-modes-256.nc", "persson-modes-512.nc")}


def main() -> None:
    print("Q4a/Q4b check (docs/open-questions/checks/q4a_mean_gap.py): measured over Persson, expected spectrum")
    for name, r in results().items():
        print(f"{name} (k_l = {r['k_l']:g}, k_s = {r['k_s']:g}, N = {r['n']}):")
        hs = sorted({k[0] for k in r["ratios"]})
        targets = sorted({k[1] for k in r["ratios"]})
        for key in ("gap", "stiffness"):
            for target in targets:
                items = []
                for h in hs:
                    band = [r["ratios"][h, target, key, "midpoint", g] for g in GAMMAS]
                    others = " / ".join(f"{r['ratios'][h, target, key, rule, 0.45]:.3f}" for rule in RULES[1:])
                    items.append(f"H = {h:g}: {band[1]:.3f} [{min(band):.3f}, {max(band):.3f}] (whole shell / per "
                                 f"mode / continuum: {others}; seed s.e. {100 * r['noise'][h, target, key]:.1f} %)")
                print(f"  {key} at A/A0 = {target:g}, γ = 0.45 [0.4–0.5], midpoint rule:")
                for item in items:
                    print(f"    {item}")
            moves = max(r["ratios"][h, t, key, "step to step"] for h in hs for t in targets)
            print(f"  {key}: the ratio moves by at most {moves:.4f} between the two steps around each A/A0")


if __name__ == "__main__":
    main()
