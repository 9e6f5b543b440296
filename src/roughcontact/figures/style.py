"""The figures' common style: Okabe-Ito palette, sizes, labels, legends, and byte-stable saving.

Every ``fig_*`` function returns a :class:`matplotlib.figure.Figure` built without pyplot (no global
figure registry, no GUI backend); :func:`save_figure` writes it as PNG and PDF with byte-identical
output on every rerun. Every figure is :data:`FIGURE_WIDTH_IN` wide and saved at :data:`PNG_DPI`, so that
the report shows every figure's text at one size (a narrower figure, scaled up to the page, has larger text);
legends sit outside the axes; colours are the Okabe-Ito palette (distinguishable with the common
colour-vision deficiencies). Every axis gets readable tick labels, a log axis over a narrow range too
(:func:`plain_log_labels`).
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
from matplotlib.ticker import FormatStrFormatter, Locator, LogLocator, MaxNLocator, NullFormatter

from ..core import precision
from ..core.files import atomic_output
from ..core.quantities import LENGTH_UNITS, PRESSURE_UNITS

#: Okabe & Ito (2008) colour-blind-safe palette, black first (reserved for theory).
OKABE_ITO = ("#000000", "#E69F00", "#56B4E9", "#009E73", "#D55E00", "#0072B2", "#CC79A7", "#F0E442")


#: Data colours: the palette without black, yellow last (weak on white).
DATA_COLOURS = OKABE_ITO[1:]


MARKERS = ("o", "s", "^", "D", "v", "P", "X")


LINESTYLES = ("-", "--", "-.", ":", (0, (5, 1)), (0, (1, 1)))


#: Width of a single-column and of a two-column figure [in]: the column a panel is sized for.
SINGLE_COLUMN_IN = 3.4


DOUBLE_COLUMN_IN = 7.0


#: Width of every figure [in] (:func:`new_figure`): one width class, so that the report shows each figure's
#: text at one size. A figure of one narrow panel centres it (constrained layout).
FIGURE_WIDTH_IN = DOUBLE_COLUMN_IN


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


#: Pixel density of every PNG [dots per inch]: with :data:`FIGURE_WIDTH_IN`, every figure is
#: ``FIGURE_WIDTH_IN * PNG_DPI`` pixels wide.
PNG_DPI = 300


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
                fig.savefig(tmp, format="png", dpi=PNG_DPI, metadata={"Software": None})
            with atomic_output(pdf) as tmp:
                fig.savefig(tmp, format="pdf",
                            metadata={"CreationDate": None, "Creator": None, "Producer": None})
    finally:
        ft_log.setLevel(level)
    return [png, pdf]


# ----------------------------------------------------------------------- helpers
def new_figure(height: float) -> Figure:
    """A constrained-layout figure :data:`FIGURE_WIDTH_IN` wide and ``height`` [in] tall, not tied to pyplot's
    state: every figure of the package has the one width (:data:`FIGURE_WIDTH_IN`)."""
    if not (np.isfinite(height) and height > 0):
        raise ValueError(f"height must be a finite number of inches > 0, got {height!r}")
    return Figure(figsize=(FIGURE_WIDTH_IN, height), layout="constrained")


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
    fig.set_size_inches(width, height + 0.19 * rows + 0.2)
    fig.legend(handles=handles, loc="outside lower center", ncols=2, title=title)


def panel_grid(n: int) -> tuple[int, int, float]:
    """``(rows, columns, height)`` [in] of a figure of ``n`` square-ish panels (one panel sized for a journal
    column, several for two), :data:`FIGURE_WIDTH_IN` wide."""
    ncols = 1 if n == 1 else min(n, 3)
    nrows = int(np.ceil(n / ncols))
    width = SINGLE_COLUMN_IN if n == 1 else DOUBLE_COLUMN_IN
    panel_w = (width - (1.3 if n == 1 else 1.4)) / ncols
    height = nrows * max(1.9, 0.85 * panel_w) + 0.3
    return nrows, ncols, height


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


#: Mantissas of the labelled ticks of a log axis, tried in turn until at least two fall in view: the decades,
#: then 1, 3; 1, 2, 5 and 1, 2, 3, 5 times them, then every integer mantissa (:class:`ReadableLogLocator`).
LOG_MANTISSAS = ((1,), (1, 3), (1, 2, 5), (1, 2, 3, 5), tuple(range(1, 10)))


class ReadableLogLocator(Locator):
    """Major ticks of a log axis, at least two in view whatever its range.

    Matplotlib's log locator puts major ticks on the decades only: an axis from 0.17 to 0.28 has none, and the
    minor ticks it labels at most one (0.2). This one takes the first set of :data:`LOG_MANTISSAS` times the
    powers of ten that puts at least two ticks in view (the decades, then 1 and 3 per decade, ...; ``dense``: from
    1, 2, 3, 5 on, when the axis spans
    less than two decades), and for an axis narrower than two neighbouring integer mantissas (0.171 to 0.178)
    evenly spaced round values (:class:`matplotlib.ticker.MaxNLocator`).
    """

    def __init__(self, dense: bool = True):
        self.dense = dense

    def __call__(self):
        lo, hi = self.axis.get_view_interval()
        return self.tick_values(lo, hi)

    def tick_values(self, vmin: float, vmax: float) -> list[float]:
        """The ticks of a log axis viewing ``[vmin, vmax]`` (either order; both > 0, else the decades)."""
        lo, hi = sorted((float(vmin), float(vmax)))
        if not (np.isfinite(lo) and np.isfinite(hi) and lo > 0):
            return list(LogLocator().tick_values(vmin, vmax))
        tries = LOG_MANTISSAS[3:] if self.dense and hi / lo < 100 else LOG_MANTISSAS
        powers = range(int(np.floor(np.log10(lo))) - 1, int(np.ceil(np.log10(hi))) + 1)
        for subs in tries:
            ticks = [m * 10.0 ** p for p in powers for m in subs]
            if sum(lo * (1 - 1e-9) <= t <= hi * (1 + 1e-9) for t in ticks) >= 2:
                return ticks
        return [t for t in MaxNLocator(nbins=3, steps=[1, 2, 2.5, 5, 10]).tick_values(lo, hi) if t > 0]


def plain_log_labels(axis, dense: bool = True) -> None:
    """Readable labels on a log axis: plain decimals (0.3, not 3x10^-1) at the ticks of
    :class:`ReadableLogLocator` (at least two in view, whatever the range; ``dense=False`` for a small inset:
    decades where two are in view), unlabelled minor ticks at every integer mantissa."""
    axis.set_major_locator(ReadableLogLocator(dense))
    axis.set_major_formatter(FormatStrFormatter("%g"))
    axis.set_minor_locator(LogLocator(subs=tuple(range(1, 10))))
    axis.set_minor_formatter(NullFormatter())


def at_interval(value: float, low: float | None = None, high: float | None = None) -> str:
    """A fitted value for a legend or title, rounded to its interval ``[low, high]`` by the report's rule
    (:func:`roughcontact.core.precision.estimate`: the decimal place of the interval's half-width; a value that is
    not 0 but would read 0 there keeps one significant figure; without an interval three figures, "—" for NaN).

    >>> at_interval(0.537, 0.15, 0.66), at_interval(1.0612, 1.0281, 1.1642), at_interval(1.466, 1.167, 3120.0)
    ('0.54', '1.06', '1')
    """
    return precision.estimate(float(value), low, high)[0]
