"""Captions true of their figure: built from the record of what the figure drew, never from text every scene shares.

A figure's caption file in ``workflow/report/`` (its *lead*) says what every rendering of it shows: the
data, the axes, how unconverged steps are drawn. What a rendering may or may not draw (an asymptote, an
asperity model at the surfaces' own bandwidth, the fitted contact evolution law and its route, the fit's
window, a 2-D map's layout or a profile's, block averaging) is in the figure's record
(:func:`roughcontact.figures.record.figure_record`): the reference lines by the ``gid`` tagged on the artist
that draws them (one of :data:`REFERENCES`), the rest noted by the figure function as it draws. :func:`caption`
appends to the lead exactly what the record holds: its notes (:data:`NOTES`), what profiles mean for the
references drawn, one sentence naming the reference lines with their line styles, and the route of the fit
drawn (:data:`ROUTES`). The figure rule writes that caption beside the figure (``figures/{figure}.caption.rst``)
with the record (``figures/{figure}.record.json``), and the report shows it.

Every reference line has its own style (:data:`REFERENCE_STYLES`) and is drawn above the data bands.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np
from matplotlib.figure import Figure

from .style import MAP_PIXELS
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
    "cel_fit": r"the fitted contact evolution law (dark grey long dashes, drawn over the data)",
    "fit_window": r"the fit's window of :math:`A/A_0` (shaded)",
    "dpbar_paper": r"the paper's power law :math:`0.21\,(A_0/A)^{0.55}` (black dashed)",
    "dpbar_fit": r"the fitted :math:`\beta\,(A_0/A)^{\mu}` (thick translucent grey)",
}

#: The routes a fit of the contact evolution law takes (the ``estimator`` of
#: :func:`roughcontact.analysis.fit.fit_cel`), as a caption names the one drawn.
ROUTES = {"paper": "the paper's route", "joint": "the joint least-squares fit"}

#: What each route does (reStructuredText), after its name in a caption.
ROUTE_DETAILS = {
    "paper": r":math:`\mu` and :math:`\beta` from a straight line through :math:`\log(\partial\bar p/\partial p_0)` "
             r"against :math:`\log(A/A_0)`, then :math:`\kappa` from :math:`E^* h'/\bar p` extrapolated along the law "
             r"to :math:`A/A_0 = 0`",
    "joint": r"all three constants at once, by least squares of :math:`\log(A/A_0)` against :math:`p_0`",
}

#: A route's name in a legend entry (short).
ROUTE_LEGEND = {"paper": "paper's route", "joint": "joint least squares"}

#: What a legend says of the fitted constants (a caption adds it where a fit is drawn).
FIT_LEGEND_NOTE = ("The legend gives each fitted constant the data constrain, rounded to its 95 % bootstrap "
                   "interval, and names the others \"not constrained by the data\" (interval wider than the "
                   "value, or the constant on a bound of the fit).")

#: Parts of a caption that hold for some renderings only, in the order a caption gives them: a figure notes
#: those that hold for it (:func:`roughcontact.figures.record.note`).
NOTES = {
    "rows_of_steps": "One row per case, one column per stored step.",
    "side_by_side": "One load step is stored: the cases stand side by side, each panel titled with its case.",
    "maps": r"On each map the heights :math:`h` are a grey-scale image (its colour bar per case, in the length "
            r"unit) and the nodal contact pressure :math:`p/E^*` is coloured over it only where :math:`p > 0`, "
            r"on the contact patches (one colour bar for the figure).",
    "block_averaged_pressure": "Maps of more than {pixels} points a side are drawn block-averaged: each pixel is "
                               "the mean of a square block of nodes, and a block shows contact where any of its "
                               "nodes is in contact.",
    "profiles_layout": r"Per case a row of profiles over a row of pressures, one column per stored step. The upper "
                       r"panel shows the profile :math:`h(x)` (grey), the "
                       r"deformed surface :math:`d - g(x)` (blue, :math:`g` the stored gap) and the rigid flat at "
                       r":math:`z = d` (black dashed), which the deformed surface touches where it is in contact "
                       r"(marked in vermilion); :math:`d = \langle h \rangle + \langle g \rangle`, the deformed "
                       r"surface keeping the profile's mean height. The lower panel shows :math:`p/E^*` along "
                       r":math:`x`.",
    "height_maps": r"A height map is drawn to scale on its own colour scale (its colour bar below it, in the "
                   r"study's length unit), its sides and grid size in its title.",
    "block_averaged": "Maps of more than {pixels} points a side are shown block-averaged: each pixel is the mean "
                      "of a square block of points.",
    "line_scans": r"A line scan (a profile: a 1-D surface) is drawn as its heights :math:`h(x)` along its length, "
                  r"its length :math:`L` and "
                  r"number of points :math:`n` in its title.",
    "profiles_contact": r"These cases are profiles (1-D surfaces in plane strain; :math:`A/A_0` is the contact "
                        r"length fraction, :math:`h'` the profile's rms slope).",
    "profiles_heights": "These surfaces are profiles (1-D surfaces): heights along a line.",
}

#: What a figure leaves out that it draws for other data, as a caption says so.
LEFT_OUT = {
    "asperity": "The asperity models are not drawn: they count the summits of a 2-D surface, which a profile "
                "has not.",
}

#: The references that are laws of 2-D surfaces, as a caption of profiles names those it draws.
PROFILE_2D_LAWS = {"bgt_limit": "the BGT limit", "cel_paper": "the paper's contact evolution law",
                   "dpbar_paper": "the paper's power law"}

#: Words a lead must not use: they name a reference, a fit's route or a layout that a rendering may leave
#: out (checked by the tests): the caption adds them from the figure's record where they apply.
CONDITIONAL_WORDS = ("BGT", "Greenwood", "Persson", "evolution law", "asperity", "power law", "fit's window",
                     "paper's route", "least-squares fit", "joint", "route", "block-averaged", "block averag",
                     "1-D", "2-D", "profile", "line scan", "grey-scale", "deformed surface", "side by side",
                     "one column per", "one row per")


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


#: The gid of a figure whose cases are profiles (1-D surfaces): :func:`roughcontact.figures.load_curves.title_figure`
#: sets it (and the other figures of profiles), and the record says so (``profiles``).
PROFILES_GID = "profiles"


def _listed(phrases: list[str], sep: str = "; ") -> str:
    """``a``, ``a and b``, or ``a; b; and c`` (``sep`` between items of three or more)."""
    if len(phrases) <= 2:
        return " and ".join(phrases)
    return sep.join(phrases[:-1]) + sep + "and " + phrases[-1]


def profiles_note(record: Mapping) -> str:
    """What profiles mean for the references a figure of profiles drew (``record``: its references): Persson's
    curves hold for a profile; the laws of 2-D surfaces it drew (:data:`PROFILE_2D_LAWS`) are drawn for
    comparison only. Empty for a record of no profiles, or one that drew none of these."""
    if not record.get("profiles"):
        return ""
    refs = list(record.get("references", ()))
    out = []
    if any(g.startswith("persson") for g in refs):
        out.append("Persson's curves hold for a profile with its own :math:`h'`.")
    laws = [PROFILE_2D_LAWS[g] for g in PROFILE_2D_LAWS if g in refs]
    if laws:
        one, names = len(laws) == 1, _listed(laws, ", ")
        text = (names[0].upper() + names[1:]
                + (" is a law" if one else " are laws") + " of 2-D surfaces, drawn for comparison only: "
                + ("it makes" if one else "they make") + " no prediction for a profile")
        if "bgt_limit" in refs or "cel_paper" in refs:
            text += (r" (no constant small-load :math:`\kappa` is known for line contacts: van Dokkum et al. "
                     "2018, Tribol. Lett. 66, 115)")
        out.append(text + ".")
    return " ".join(out)


def fit_sentence(record: Mapping) -> str:
    """The route of the fits a figure drew (``record["fits"]``) and their window, with what the legend says of
    the constants; empty without a fit."""
    routes = [r for r in ROUTES if any(f["route"] == r for f in record.get("fits", ()))]
    if not routes:
        return ""
    named = _listed([f"{ROUTES[r]} ({ROUTE_DETAILS[r]})" for r in routes])
    window = record.get("window")
    over = (f" over :math:`A/A_0` from {window[0]:g} to {window[1]:g}" if window else "")
    return f"The fit drawn is {named}{over}. {FIT_LEGEND_NOTE}"


def caption(lead: str, record: Mapping) -> str:
    """The caption of a figure from its ``lead`` (reStructuredText) and its ``record``
    (:func:`roughcontact.figures.record.figure_record`): the lead, then the notes that hold for it
    (:data:`NOTES`), what profiles mean for its references (:func:`profiles_note`) and what it leaves out
    (:data:`LEFT_OUT`), the load steps it marks unresolved (:func:`~.unresolved.unresolved_note`), one sentence
    naming the reference lines it shows (none when it shows none), and the
    route of its fit (:func:`fit_sentence`)."""
    out = lead.rstrip() + "\n"
    for key in record.get("notes", ()):
        out += "\n" + NOTES[key].replace("{pixels}", str(MAP_PIXELS)) + "\n"
    profile = " ".join(t for t in [profiles_note(record), *(LEFT_OUT[k] for k in record.get("left_out", ()))] if t)
    if profile:
        out += "\n" + profile + "\n"
    out += unresolved_note(record.get("unresolved", ()))
    gids = [g for g in REFERENCES if g in record.get("references", ())]
    if gids:
        out += "\nDrawn with the data: " + _listed([REFERENCES[g] for g in gids]) + ".\n"
    fits = fit_sentence(record)
    if fits:
        out += "\n" + fits + "\n"
    return out
