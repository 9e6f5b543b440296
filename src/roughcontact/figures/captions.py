"""Captions true of their figure: the reference lines a caption names are those the figure drew.

A figure's caption file in ``workflow/report/`` (its *lead*) says what every rendering of it shows: the
data, the axes, how unconverged steps are drawn. What a rendering may or may not draw (an asymptote, an
asperity model at the surfaces' own bandwidth, the fitted contact evolution law, the fit's window) is tagged
on the artist that draws it, by its ``gid`` (one of :data:`REFERENCES`), and :func:`caption` appends one
sentence naming exactly the tagged artists the figure holds, each with its line style. The figure rule writes
that caption beside the figure (``figures/{figure}.caption.rst``) and the report shows it.

Every reference line has its own style (:data:`REFERENCE_STYLES`) and is drawn above the data bands.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
from matplotlib.figure import Figure

from .unresolved import unresolved_note

#: Styles of the reference lines (matplotlib keyword arguments), one per kind, all distinct and above
#: the data bands (zorder 2) and the data lines (2.5). The asperity models' colour depends on the
#: bandwidth (:func:`roughcontact.figures.load_curves.asperity_alphas`); their style on the model.
REFERENCE_STYLES = {
    "bgt_limit": {"color": "black", "lw": 0.9, "ls": "-", "zorder": 3},
    "cel_fit": {"color": "0.3", "lw": 1.8, "ls": (0, (7, 2.5)), "zorder": 4.5},
    "cel_paper": {"color": "black", "lw": 1.3, "ls": (0, (3, 1.2, 1, 1.2, 1, 1.2)), "zorder": 4},
    "asperity_bgt": {"lw": 1.1, "ls": (0, (5, 1.5, 1, 1.5)), "zorder": 3},
    "asperity_greenwood": {"lw": 1.2, "ls": (0, (1, 1.3)), "zorder": 3},
}

#: Every tag a figure may put on a reference artist, in the order a caption names them, with its phrase
#: (reStructuredText, the line style included).
REFERENCES = {
    "bgt_limit": r"the BGT small-load limit :math:`\kappa_\mathrm{BGT} = \sqrt{2\pi}` (thin black solid)",
    "persson_limit": r"Persson's small-load limit :math:`\kappa = \sqrt{8/\pi}` (purple dashed)",
    "persson_erf": r"Persson's full erf curve (thick translucent purple, under his limit at small load)",
    "asperity_bgt_paper": r"the finite-load BGT asperity model at the paper's bandwidth :math:`\alpha = 2` "
                          r"(dark grey dash-dot)",
    "asperity_greenwood_paper": r"Greenwood's (2006) asperity model at :math:`\alpha = 2` (dark grey dotted)",
    "asperity_bgt_own": r"the BGT asperity model at the surfaces' own mean :math:`\alpha` (light grey dash-dot)",
    "asperity_greenwood_own": r"Greenwood's asperity model at the surfaces' own mean :math:`\alpha` "
                              r"(light grey dotted)",
    "cel_paper": r"the paper's contact evolution law (:math:`\kappa = 1.145\sqrt{2\pi}`, :math:`\mu = 0.55`, "
                 r":math:`\beta = 0.21`; black dash-dot-dot)",
    "cel_fit": r"the contact evolution law fitted to this run (dark grey long dashes, drawn over the data)",
    "fit_window": r"the fit's window of :math:`A/A_0` (shaded)",
    "dpbar_paper": r"the paper's power law :math:`0.21\,(A_0/A)^{0.55}` (black dashed)",
    "dpbar_fit": r"this run's fitted :math:`\beta\,(A_0/A)^{\mu}` (thick translucent grey)",
}

#: Words a lead must not use: they name a reference that a rendering may leave out (checked by the tests).
CONDITIONAL_WORDS = ("BGT", "Greenwood", "Persson", "evolution law", "asperity", "power law", "fit's window")


def tagged(artists: Iterable) -> list:
    """The artists of ``artists`` tagged with a gid of :data:`REFERENCES`."""
    return [a for a in artists if a.get_gid() in REFERENCES]


def reference_artists(fig: Figure) -> list:
    """Every visible tagged artist on a visible axes of ``fig`` (lines and shaded spans)."""
    out = []
    for ax in fig.axes:
        if ax.get_visible():
            out += [a for a in tagged([*ax.lines, *ax.patches, *ax.collections]) if a.get_visible()]
    return out


def in_view(artist) -> bool:
    """Whether a tagged artist shows: a line with a finite point inside its axes' limits, or a shaded span
    (a patch or collection) overlapping them."""
    ax = artist.axes
    (x0, x1), (y0, y1) = sorted(ax.get_xlim()), sorted(ax.get_ylim())
    if hasattr(artist, "get_xydata"):
        xy = np.asarray(artist.get_xydata(), dtype=float).reshape(-1, 2)
        inside = (np.isfinite(xy).all(axis=1) & (xy[:, 0] >= x0) & (xy[:, 0] <= x1)
                  & (xy[:, 1] >= y0) & (xy[:, 1] <= y1))
        return bool(inside.any())
    box = artist.get_window_extent().transformed(ax.transData.inverted())
    return bool(box.x1 >= x0 and box.x0 <= x1 and box.y1 >= y0 and box.y0 <= y1)


def drawn(fig: Figure) -> list[str]:
    """The gids of :data:`REFERENCES` that ``fig`` shows (:func:`in_view`), in :data:`REFERENCES`' order."""
    shown = {a.get_gid() for a in reference_artists(fig) if in_view(a)}
    return [gid for gid in REFERENCES if gid in shown]


#: The gid of a figure whose cases are profiles (1-D surfaces, plane strain):
#: :func:`roughcontact.figures.load_curves.title_figure` sets it, :func:`caption` adds :data:`PROFILES_NOTE`.
PROFILES_GID = "profiles"
#: What a caption of profiles says of its references (:mod:`roughcontact.theory.profiles`).
PROFILES_NOTE = (
    "\nThese cases are profiles (1-D surfaces in plane strain; A/A0 is the contact length fraction, h' the "
    "profile's rms slope). Persson's curves hold for a profile with its own h'. The BGT limit and the paper's "
    "contact evolution law and power law are laws of 2-D surfaces, drawn for comparison only: they make no "
    "prediction for a profile (no constant small-load kappa is known for line contacts: van Dokkum et al. 2018, "
    "Tribol. Lett. 66, 115), and the asperity models of a 2-D surface's summits are not drawn.\n")


def caption(lead: str, fig: Figure) -> str:
    """The caption of ``fig``: its ``lead`` (reStructuredText), then one sentence naming the reference lines
    it shows (:func:`drawn`), or none when it shows none; a figure of profiles (gid :data:`PROFILES_GID`)
    also :data:`PROFILES_NOTE`."""
    lead = lead.rstrip() + "\n" + (PROFILES_NOTE if fig.get_gid() == PROFILES_GID else "") + unresolved_note(fig)
    gids = drawn(fig)
    if not gids:
        return lead
    phrases = [REFERENCES[g] for g in gids]
    listed = phrases[0] if len(phrases) == 1 else "; ".join(phrases[:-1]) + "; and " + phrases[-1]
    return lead + "\nDrawn with the data: " + listed + ".\n"
