"""The CEL fit as a CSV table: one row per group, estimator and constant.
"""

from __future__ import annotations

import io

import numpy as np
import xarray as xr


def _csv_float(x) -> str:
    x = float(x)
    return "" if not np.isfinite(x) else f"{x:.6g}"


def to_csv_table(fit_ds: xr.Dataset) -> str:
    """Human-readable CSV of a :func:`fit_cel` or :func:`fit_topographies` result.

    One row per group/estimator/constant (floats with 6 significant digits; empty cell for
    NaN). For :func:`fit_cel`, columns ``k_l, k_s, H_group, estimator, constant, value,
    stderr, bootstrap_stderr, ci_low, ci_high, constrained, n_points, n_seeds, n_boot_ok,
    paper_value, paper_stderr``; groups without cases are omitted; rows are sorted by k_l,
    k_s, then the dataset's H_group, estimator, constant order. For
    :func:`fit_topographies` (a dataset with ``n_topographies``), columns ``group, estimator,
    constant, value, stderr, bootstrap_stderr, ci_low, ci_high, constrained, n_points,
    n_topographies, n_boot_ok, paper_value, paper_stderr`` with ``group`` =
    ``"pooled (N topographies)"``; no row if no topography was fitted.

    Parameters
    ----------
    fit_ds : xarray.Dataset
        Output of :func:`fit_cel` or :func:`fit_topographies`.

    Returns
    -------
    str
        The table, with a header line and a trailing newline.
    """
    measured = "n_topographies" in fit_ds
    needed = ("value", "stderr", "bootstrap_stderr", "ci_low", "ci_high", "constrained", "n_points",
              "n_topographies" if measured else "n_seeds", "n_boot_ok", "paper_value", "paper_stderr")
    missing = [v for v in needed if v not in fit_ds]
    if missing:
        raise ValueError(f"fit_ds lacks {missing}; pass the output of fit_cel or fit_topographies")
    if measured:
        return _csv_table_topographies(fit_ds)
    fmt = _csv_float

    buf = io.StringIO()
    cols = ["k_l", "k_s", "H_group", "estimator", "constant", "value", "stderr", "bootstrap_stderr",
            "ci_low", "ci_high", "constrained", "n_points", "n_seeds", "n_boot_ok", "paper_value", "paper_stderr"]
    buf.write(",".join(cols) + "\n")
    for kl in fit_ds["k_l"].values:
        for ks in fit_ds["k_s"].values:
            for hg in fit_ds["H_group"].values:
                sel = dict(k_l=kl, k_s=ks, H_group=hg)
                n_s = int(fit_ds["n_seeds"].sel(sel))
                if n_s == 0:
                    continue
                for m in fit_ds["estimator"].values:
                    for c in fit_ds["constant"].values:
                        full = dict(sel, estimator=m, constant=c)
                        row = [fmt(kl), fmt(ks), str(hg), str(m), str(c)]
                        row += [fmt(fit_ds[v].sel(full)) for v in ("value", "stderr", "bootstrap_stderr",
                                                                 "ci_low", "ci_high")]
                        row += ["yes" if int(fit_ds["constrained"].sel(full)) else "no",
                                str(int(fit_ds["n_points"].sel(full))), str(n_s),
                                str(int(fit_ds["n_boot_ok"].sel(dict(sel, estimator=m))))]
                        row += [fmt(fit_ds["paper_value"].sel(constant=c)),
                                fmt(fit_ds["paper_stderr"].sel(constant=c))]
                        buf.write(",".join(row) + "\n")
    return buf.getvalue()


#: Columns of the CSV table of a :func:`fit_topographies` result.
TOPOGRAPHY_CSV_COLUMNS = ("group", "estimator", "constant", "value", "stderr", "bootstrap_stderr", "ci_low",
                          "ci_high", "constrained", "n_points", "n_topographies", "n_boot_ok", "paper_value",
                          "paper_stderr")


def _csv_table_topographies(fit_ds: xr.Dataset) -> str:
    buf = io.StringIO()
    buf.write(",".join(TOPOGRAPHY_CSV_COLUMNS) + "\n")
    n_t = int(fit_ds["n_topographies"])
    if n_t == 0:
        return buf.getvalue()
    # A label without commas keeps every cell unquoted, like fit_cel's table.
    group = f"pooled ({n_t} topograph{'y' if n_t == 1 else 'ies'})"
    for m in fit_ds["estimator"].values:
        for c in fit_ds["constant"].values:
            full = dict(estimator=m, constant=c)
            row = [group, str(m), str(c)]
            row += [_csv_float(fit_ds[v].sel(full)) for v in ("value", "stderr", "bootstrap_stderr", "ci_low",
                                                              "ci_high")]
            row += ["yes" if int(fit_ds["constrained"].sel(full)) else "no", str(int(fit_ds["n_points"].sel(full))),
                    str(n_t), str(int(fit_ds["n_boot_ok"].sel(estimator=m)))]
            row += [_csv_float(fit_ds[v].sel(constant=c)) for v in ("paper_value", "paper_stderr")]
            buf.write(",".join(row) + "\n")
    return buf.getvalue()
