"""The figures' common style: Okabe-Ito palette, sizes, labels, legends, and byte-stable saving.

Every ``fig_*`` function returns a :class:`matplotlib.figure.Figure` built without pyplot (no global
figure registry, no GUI backend); :func:`save_figure` writes it as PNG and PDF with byte-identical
output on every rerun. Single-column figures are 3.4 in wide, multi-panel ones 7 in; legends sit
outside the axes; colours are the Okabe-Ito palette (distinguishable with the common colour-vision
deficiencies).
"""

from __future__ import annotations

import logging
import os
import re
from collections.abc import Sequence
from pathlib import Path

import matplotlib
import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import FormatStrFormatter, FuncFormatter

from ..core.files import atomic_output
from ..core.quantities import LENGTH_UNITS, PRESSURE_UNITS

#: Okabe & Ito (2008) colour-blind-safe palette, black first (reserved for theory).
OKABE_ITO = ("#000000", "#E69F00", "#56B4E9", "#009E73", "#D55E00", "#0072B2", "#CC79A7", "#F0E442")


#: Data colours: the palette without black, yellow last (weak on white).
DATA_COLOURS = OKABE_ITO[1:]


MARKERS = ("o", "s", "^", "D", "v", "P", "X")


LINESTYLES = ("-", "--", "-.", ":", (0, (5, 1)), (0, (1, 1)))


#: Width of a single-column and of a two-column figure [in].
SINGLE_COLUMN_IN = 3.4


DOUBLE_COLUMN_IN = 7.0


#: The package's matplotlib settings (fonts sized for a journal column, Okabe-Ito colours,
#: reproducible PDF): draw inside ``matplotlib.rc_context(STYLE)``.
STYLE = {
    "font.size": 8,
    "axes.labelsize": 8,
    "axes.titlesize": 8,
    "legend.fontsize": 7,
    "legend.title_fontsize": 7,
    "xtick.labelsize": 7,
    "ytick.labelsize": 7,
    "lines.linewidth": 1.0,
    "lines.markersize": 3.0,
    "axes.linewidth": 0.6,
    "errorbar.capsize": 1.5,
    "legend.frameon": False,
    "image.cmap": "cividis",
    "pdf.fonttype": 42,
    "svg.hashsalt": "roughcontact",
}


_PNG_DPI = 300


#: Largest side, in pixels, of a map as drawn: larger maps are block-averaged (:func:`block_mean`; a
#: panel is ~2 in wide, so more pixels only bloat the PDF).
MAP_PIXELS = 512


# ------------------------------------------------------------------------ saving
def save_figure(fig: Figure, path: str | os.PathLike) -> list[Path]:
    """Write ``fig`` as ``<path>.png`` (300 dpi) and ``<path>.pdf``, byte-reproducibly.

    A ``.png`` or ``.pdf`` suffix on ``path`` is replaced, so either output name may be
    passed. Reproducibility: PNG drops the ``Software`` text chunk; PDF drops
    ``CreationDate``, ``Creator`` and ``Producer`` (dates and versions are the only
    varying bytes; Agg rasterisation and PDF object numbering are deterministic, and
    TrueType embedding (``pdf.fonttype`` 42) subsets fonts deterministically).
    Each file is written atomically (:func:`roughcontact.core.files.atomic_output`): an
    interrupted save leaves the previous complete file or none, never a truncated one,
    and the files get the mode the umask gives.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or os.PathLike
        Output path without extension, or with ``.png`` / ``.pdf``; parent folders are
        created.

    Returns
    -------
    list of pathlib.Path
        ``[png_path, pdf_path]``.
    """
    if not isinstance(fig, Figure):
        raise ValueError(f"fig must be a matplotlib Figure, got {type(fig).__name__}")
    base = Path(path)
    if base.suffix.lower() in (".png", ".pdf"):
        base = base.with_suffix("")
    if not base.name:
        raise ValueError(f"path must name a file, got {path!r}")
    base.parent.mkdir(parents=True, exist_ok=True)
    png, pdf = base.with_suffix(".png"), base.with_suffix(".pdf")
    # Subsetting DejaVu's display-size glyphs (big radicals) makes fontTools warn about
    # the font's zero timestamps; the output is unaffected, so keep the logs clean.
    ft_log = logging.getLogger("fontTools")
    level = ft_log.level
    ft_log.setLevel(logging.ERROR)
    try:
        with matplotlib.rc_context({"pdf.fonttype": 42, "svg.hashsalt": "roughcontact"}):
            with atomic_output(png) as tmp:
                fig.savefig(tmp, format="png", dpi=_PNG_DPI, metadata={"Software": None})
            with atomic_output(pdf) as tmp:
                fig.savefig(tmp, format="pdf",
                            metadata={"CreationDate": None, "Creator": None, "Producer": None})
    finally:
        ft_log.setLevel(level)
    return [png, pdf]


# ----------------------------------------------------------------------- helpers
def new_figure(width: float, height: float) -> Figure:
    """A constrained-layout figure of ``width`` x ``height`` inches, not tied to pyplot's state."""
    return Figure(figsize=(width, height), layout="constrained")


def require(ds: xr.Dataset, name: str, variables: Sequence[str]) -> None:
    """Raise ``ValueError`` naming ``name`` unless ``ds`` is a Dataset holding every one of ``variables``."""
    if not isinstance(ds, xr.Dataset):
        raise ValueError(f"{name} must be an xarray.Dataset, got {type(ds).__name__}")
    missing = [v for v in variables if v not in ds]
    if missing:
        raise ValueError(f"{name} lacks variable(s) {missing}")



def block_mean(h: np.ndarray, pixels: int) -> np.ndarray:
    """``h`` (nx, ny) averaged over ``f x f`` blocks (``f = ceil(max(nx, ny) / pixels)``; ragged edges cropped)."""
    f = -(-max(h.shape) // pixels)
    if f <= 1:
        return h
    mx, my = h.shape[0] // f, h.shape[1] // f
    return h[:mx * f, :my * f].reshape(mx, f, my, f).mean(axis=(1, 3))


def pick(values: np.ndarray, wanted, name: str) -> list[float]:
    """The values of ``values`` matching ``wanted`` (to 1e-9 relative), all of them when ``wanted`` is None; a
    ValueError naming ``name`` for a wanted value that is not there."""
    have = [float(v) for v in values]
    if wanted is None:
        return have
    out = []
    for w in np.atleast_1d(wanted):
        matches = [h for h in have if np.isclose(h, float(w), rtol=1e-9, atol=0)]
        if not matches:
            raise ValueError(f"{name}={float(w)!r} is not in the data; available: {have}")
        out.append(matches[0])
    return out


#: One factor of a unit string of :func:`roughcontact.core.quantities.cf_unit` (``um``, ``um^-2``), of
#: :func:`number_unit` (``um^(-1/2)``) or of files of older versions (``um**-2``, ``um^-0.5``).
_UNIT_FACTOR = re.compile(r"^([A-Za-z]+)(?:(?:\^|\*\*)\(?([-+]?\d+(?:/\d+|\.\d+)?)\)?)?$")


_UNIT_SYMBOLS = frozenset(LENGTH_UNITS + PRESSURE_UNITS + ("s",)) - {"1"}


def unit_tex(units: str) -> str:
    """A unit string as mathtext, upright, factors separated by a thin space.

    The strings of :func:`roughcontact.core.quantities.cf_unit` and :func:`number_unit`: ``"um^(-1/2)"``
    -> ``$\\mathrm{\\mu m}^{-1/2}$``, ``"MPa um^-1"`` -> ``$\\mathrm{MPa}\\,\\mathrm{\\mu m}^{-1}$``,
    ``"1"`` -> ``"1"``. Other strings (files of older versions) as one upright word with
    its power: ``"length unit^-1/2"`` -> ``$(\\mathrm{length\\ unit})^{-1/2}$``.
    """
    units = units.strip()
    if units in ("", "1"):
        return "1"
    factors = [_UNIT_FACTOR.match(f) for f in units.split()]
    if all(m is not None and m.group(1) in _UNIT_SYMBOLS for m in factors):
        parts = []
        for m in factors:
            base, power = m.groups()
            tex = r"\mathrm{" + (r"\mu m" if base == "um" else base) + "}"
            parts.append(f"{tex}^{{{power}}}" if power else tex)
        return "$" + r"\,".join(parts) + "$"
    base, _, power = units.partition("^")
    tex = r"\mathrm{" + base.strip().replace(" ", r"\ ") + "}"
    if " " in base.strip() and power:
        tex = f"({tex})"
    return f"${tex}^{{{power}}}$" if power else f"${tex}$"


def number_unit(attrs) -> str:
    """The unit a variable's number is in, for a label: its ``units``, or for a value written for lengths in
    a reference unit (:func:`roughcontact.core.quantities.per_reference_length`) that unit to its power, e.g.
    ``"um^(-1/2)"`` for ``epsilon`` (``units`` ``"1"``, ``reference_length_units`` ``"um"``, power ``"-1/2"``)."""
    ref, power = attrs.get("reference_length_units"), attrs.get("reference_length_power")
    if ref is None or power is None or ref == "1":
        return str(attrs.get("units", "1"))
    return f"{ref}^({power})"


def fmt(v: float) -> str:
    """A number as a short label (``%g``)."""
    return f"{float(v):g}"


def lambda_label(k: float, which: str) -> str:
    """``lambda = L/k`` as the paper writes it: ``L`` itself for ``k = 1``."""
    return rf"$\lambda_{which} = L$" if float(k) == 1.0 else rf"$\lambda_{which} = L/{fmt(k)}$"


def legend_below(fig: Figure, handles: list, title: str) -> None:
    """A two-column legend under the panels; the figure grows by its height, the panels keep theirs."""
    rows = int(np.ceil(len(handles) / 2)) + 1
    width, height = fig.get_size_inches()
    fig.set_size_inches(max(width, DOUBLE_COLUMN_IN), height + 0.19 * rows + 0.2)
    fig.legend(handles=handles, loc="outside lower center", ncols=2, title=title)


def panel_grid(n: int) -> tuple[int, int, float, float]:
    """``(rows, columns, width, height)`` [in] of a figure of ``n`` square-ish panels in a journal column or two."""
    ncols = 1 if n == 1 else min(n, 3)
    nrows = int(np.ceil(n / ncols))
    width = SINGLE_COLUMN_IN if n == 1 else DOUBLE_COLUMN_IN
    panel_w = (width - (1.3 if n == 1 else 1.4)) / ncols
    height = nrows * max(1.9, 0.85 * panel_w) + 0.3
    return nrows, ncols, width + (1.3 if n == 1 else 0.0), height


def family_styles(k_ls: Sequence[float], hs: Sequence[float]):
    """Colour by Hurst exponent, marker and line style by long cutoff: three dicts keyed by ``H`` or ``k_l``."""
    colour = {h: DATA_COLOURS[i % len(DATA_COLOURS)] for i, h in enumerate(hs)}
    marker = {k: MARKERS[i % len(MARKERS)] for i, k in enumerate(k_ls)}
    style = {k: LINESTYLES[i % len(LINESTYLES)] for i, k in enumerate(k_ls)}
    return colour, marker, style


def family_handles(k_ls, hs, colour, marker, style) -> list[Line2D]:
    """Legend handles of the families: one line per ``H`` (its colour), one marker and style per ``k_l``."""
    handles = [Line2D([], [], color=colour[h], lw=1.5, label=f"$H = {fmt(h)}$") for h in hs]
    handles += [Line2D([], [], color="0.35", marker=marker[k], ls=style[k], label=lambda_label(k, "l"))
                for k in k_ls]
    return handles


def plain_log_labels(axis) -> None:
    """Plain decimals on a log axis (0.3, not 3x10^-1): the decades, and 2, 3, 5 times them
    where the axis spans less than two decades (decided when drawn, from its limits)."""
    def minor(v, _pos):
        lo, hi = sorted(axis.get_view_interval())
        mantissa = v / 10.0 ** np.floor(np.log10(v) + 1e-9)
        return f"{v:g}" if hi / lo < 100 and any(np.isclose(mantissa, (2, 3, 5))) else ""

    axis.set_major_formatter(FormatStrFormatter("%g"))
    axis.set_minor_formatter(FuncFormatter(minor))
