"""Independent check of Q4d: the percolation threshold by each definition of "wraps", and its spread (issue 61).

Reads ``cluster_wrapping`` of percolation.nc (the page's 60 surfaces) and percolation-2048.nc (12
surfaces at λ_s = 64 Δx). The variable holds CF flag bits per (H, seed, step, connectivity):
1 = a cluster wraps the periodic cell in x, 2 = in y, 4 = one cluster in both directions (two
independent winding vectors). Per surface and definition, the first step whose bits match and the
step before it bracket the threshold; a definition's threshold is the mean of the bracket midpoints.

Run: ``python docs/open-questions/checks/q4d_percolation.py``; its output is q4d_percolation.txt.
"""

from __future__ import annotations

import numpy as np
from common import DATA, load, one_cell

DEFINITIONS = {"x or y": 1 | 2, "in x": 1, "in y": 2, "both directions": 4}
DAPP = 0.42


def brackets(ds, bits: int, connectivity: int) -> np.ndarray:
    """Per surface ``(below, at)``: A/A0 of the step before the first wrapping one, and of that step."""
    codes = ds["cluster_wrapping"].sel(connectivity=connectivity).values  # (H, seed, step)
    area = ds["area_fraction"].values
    out = []
    for i in range(codes.shape[0]):
        for j in range(codes.shape[1]):
            hit = np.flatnonzero(codes[i, j] & bits)
            k = int(hit[0])
            assert 0 < k, "a surface wraps at the first step: no bracket"
            out.append((area[i, j, k - 1], area[i, j, k]))
    return np.array(out)


def threshold(b: np.ndarray) -> dict:
    mid = b.mean(axis=1)
    return {"threshold": float(mid.mean()), "sem": float(mid.std(ddof=1) / np.sqrt(mid.size)),
            "half_step": float(0.5 * (b[:, 1] - b[:, 0]).max()), "n": int(mid.size),
            "below": float(b[:, 0].mean()), "at": float(b[:, 1].mean())}


def results() -> dict:
    out = {}
    for name in ("percolation.nc", "percolation-2048.nc"):
        ds = one_cell(load(DATA / name))
        assert list(ds["cluster_wrapping"].attrs["flag_meanings"].split()) == ["wraps_x", "wraps_y", "wraps_both"]
        for conn in (4, 8):
            defs = {d: threshold(brackets(ds, bits, conn)) for d, bits in DEFINITIONS.items()}
            values = [d["threshold"] for d in defs.values()]
            one = 0.5 * (defs["in x"]["threshold"] + defs["in y"]["threshold"])
            half_range = 0.5 * (max(values) - min(values))
            u = max(half_range, max(defs[k]["sem"] for k in ("in x", "in y")),
                    max(defs[k]["half_step"] for k in ("in x", "in y")))
            out[name, conn] = {"definitions": defs, "one direction": one, "half_range": half_range, "u": u}
    return out


def verdict(m: float, u: float) -> str:
    off = abs(m - DAPP)
    return "yes" if off <= 2 * u and u <= 0.01 else "partly" if off <= max(2 * u, 0.05) else "no"


def main() -> None:
    print("Q4d check (docs/open-questions/checks/q4d_percolation.py): first wrapping step per surface")
    for (name, conn), r in results().items():
        print(f"{name}, {conn}-connected clusters:")
        for d, t in r["definitions"].items():
            print(f"  {d}: threshold {t['threshold']:.4f} (brackets {t['below']:.4f} → {t['at']:.4f} on average; "
                  f"seed standard error {t['sem']:.4f}, half the widest bracket {t['half_step']:.4f}, {t['n']} "
                  "surfaces)")
        print(f"  one direction (mean of in x and in y): {r['one direction']:.4f} ± {r['u']:.4f} (the definitions' "
              f"half-range {r['half_range']:.4f}); |threshold − {DAPP}| = {abs(r['one direction'] - DAPP):.4f}; "
              f"rule's verdict: {verdict(r['one direction'], r['u'])}")


if __name__ == "__main__":
    main()
