"""Compare the results of two runs of one scene: every NetCDF (and CSV) file, byte for byte.

usage: python compare_results.py LOCAL_RESULTS SLURM_RESULTS

Both trees must hold the same set of *.nc and *.csv files, and each pair must be
byte-identical (the pipeline writes no timestamps, host names or paths into its outputs).
For a NetCDF pair that differs, the xarray difference is printed. Exit status 0 when all
match, 1 otherwise.
"""
import filecmp
import sys
from pathlib import Path

PATTERNS = ("*.nc", "*.csv")


def _files(root: Path) -> set[Path]:
    return {p.relative_to(root) for pattern in PATTERNS for p in root.rglob(pattern)}


def _numeric_diffs(da, db) -> str:
    """Largest absolute difference of each numeric variable present in both with equal shape."""
    import numpy as np

    lines = []
    for name in sorted(set(da.variables) & set(db.variables)):
        a, b = da[name].values, db[name].values
        if a.shape != b.shape or not (np.issubdtype(a.dtype, np.number) and np.issubdtype(b.dtype, np.number)):
            continue
        diff = np.abs(a.astype(float) - b.astype(float))
        both_nan = np.isnan(a.astype(float)) & np.isnan(b.astype(float))
        diff = np.where(both_nan, 0.0, diff)
        if diff.size and (np.nanmax(diff) > 0 or np.isnan(diff).any()):
            where = np.unravel_index(int(np.nanargmax(np.nan_to_num(diff, nan=np.inf))), diff.shape)
            lines.append(f"{name}: max |local - slurm| = {np.nanmax(diff):.3e} at index {tuple(int(i) for i in where)}")
    return ("\n" + "\n".join(lines)) if lines else ""


def _explain(a: Path, b: Path) -> str:
    if a.suffix != ".nc":
        return "contents differ"
    try:
        import xarray as xr

        with xr.open_dataset(a) as da, xr.open_dataset(b) as db:
            try:
                xr.testing.assert_identical(da.load(), db.load())
            except AssertionError as err:
                return str(err) + _numeric_diffs(da, db)
        return "bytes differ, but xarray finds the datasets identical (encoding or layout)"
    except Exception as err:  # noqa: BLE001 - report, do not hide the mismatch
        return f"bytes differ; could not open with xarray: {err!r}"


def main(local: str, slurm: str) -> int:
    a_root, b_root = Path(local), Path(slurm)
    a_files, b_files = _files(a_root), _files(b_root)
    problems = []
    for rel in sorted(a_files - b_files):
        problems.append(f"only in the local run: {rel}")
    for rel in sorted(b_files - a_files):
        problems.append(f"only in the SLURM run: {rel}")
    common = sorted(a_files & b_files)
    n_nc = sum(1 for rel in common if rel.suffix == ".nc")
    for rel in common:
        if not filecmp.cmp(a_root / rel, b_root / rel, shallow=False):
            problems.append(f"differs: {rel}\n    " + _explain(a_root / rel, b_root / rel).replace("\n", "\n    "))
    if not common:
        problems.append(f"no *.nc or *.csv files found under {a_root} and {b_root}")
    if problems:
        print(f"MISMATCH: {len(problems)} problem(s) comparing {a_root} with {b_root}:")
        for p in problems:
            print("  " + p)
        return 1
    print(f"MATCH: {len(common)} files ({n_nc} NetCDF) byte-identical between the local and SLURM runs")
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1], sys.argv[2]))
