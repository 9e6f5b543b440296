"""What a figure drew, recorded as it draws it: the source of its caption and of ``{figure}.record.json``.

A figure function notes on its figure, as it draws, what a caption must say and a reader may check: its data
series (:func:`note_series`), each fitted curve with the fit's route and where it applies (:func:`note_fit`),
the parts of the caption that hold only for some renderings (:func:`note`: a 2-D map's layout or a profile's,
block averaging, profiles) and what it leaves out that it draws for other data (:func:`note_left_out`). The
reference lines need no note: they carry their tag (a gid of :data:`~.captions.REFERENCES`) and
:func:`~.captions.drawn` finds those in view. :func:`figure_record` gathers it all into the figure's record, a
JSON-able mapping; :func:`roughcontact.figures.captions.caption` builds the caption from it alone, and the
figure rule writes it beside the figure (:func:`record_json`), so that a reader's test can check the caption,
legend and title against what was drawn.

The record's keys: ``figure`` (its registered name), ``title``, ``references`` (the gids of the reference
lines in view, in :data:`~.captions.REFERENCES`' order), ``fits`` (``{"route", "label", "where"}`` of each fitted
curve in view: ``route`` a key of :data:`~.captions.ROUTES`, ``label`` its legend entry), ``window`` (the fit's
window ``[low, high]`` of ``A/A0`` where a fit is drawn, else null), ``series`` (the data series drawn, by name),
``profiles`` (whether the cases are profiles), ``notes`` (keys of :data:`~.captions.NOTES`), ``left_out``
(keys of :data:`~.captions.LEFT_OUT`) and ``unresolved`` (the largest patch's node count of each load step the
figure marks unresolved, sorted: :mod:`~.unresolved`).
"""

from __future__ import annotations

import json
import weakref
from collections.abc import Iterable, Sequence

import numpy as np
from matplotlib.figure import Figure

from .captions import LEFT_OUT, NOTES, PROFILES_GID, ROUTES, drawn, in_view
from .unresolved import shown_nodes

#: What each figure has noted so far (no strong reference: a figure closed is forgotten).
_NOTES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _notes(fig: Figure) -> dict:
    if not isinstance(fig, Figure):
        raise ValueError(f"fig must be a matplotlib Figure, got {type(fig).__name__}")
    return _NOTES.setdefault(fig, {"series": [], "fits": [], "notes": [], "left_out": []})


def note_series(fig: Figure, names: Iterable[str]) -> None:
    """Record the data series ``names`` (e.g. ``"k_l = 4, k_s = 32, H = 0.36"``, a file's name) drawn on ``fig``."""
    _notes(fig)["series"].extend(str(n) for n in names)


def note_fit(fig: Figure, artist, route: str, label: str, where: str, window: Sequence[float]) -> None:
    """Record a fitted curve: its ``artist`` (a line on ``fig``'s axes: the record keeps the fit only while it
    is in view), the fit's ``route`` (a key of :data:`~.captions.ROUTES`), its legend ``label``, the group it
    was fitted to (``where``, plain text) and the fit's ``window`` ``(low, high)`` of ``A/A0`` [1]."""
    if route not in ROUTES:
        raise ValueError(f"route must be one of {sorted(ROUTES)}, got {route!r}")
    low, high = (float(v) for v in window)
    _notes(fig)["fits"].append((artist, {"route": route, "label": str(label), "where": str(where)}, [low, high]))


def note(fig: Figure, *keys: str) -> None:
    """Record that the caption's notes ``keys`` (of :data:`~.captions.NOTES`) hold for this rendering."""
    unknown = [k for k in keys if k not in NOTES]
    if unknown:
        raise ValueError(f"unknown caption notes {unknown}; known: {sorted(NOTES)}")
    _notes(fig)["notes"].extend(k for k in keys if k not in _notes(fig)["notes"])


def note_left_out(fig: Figure, *keys: str) -> None:
    """Record what ``fig`` leaves out that it draws for other data (keys of :data:`~.captions.LEFT_OUT`)."""
    unknown = [k for k in keys if k not in LEFT_OUT]
    if unknown:
        raise ValueError(f"unknown left-out items {unknown}; known: {sorted(LEFT_OUT)}")
    _notes(fig)["left_out"].extend(k for k in keys if k not in _notes(fig)["left_out"])


def _shown(artist) -> bool:
    """Whether a noted fit's artist shows: on a visible axes, visible, with a point in view."""
    ax = getattr(artist, "axes", None)
    return ax is not None and ax.get_visible() and artist.get_visible() and in_view(artist)


def figure_record(name: str, fig: Figure) -> dict:
    """The record of what ``fig`` (the registered figure ``name``) drew: see the module for its keys."""
    noted = _notes(fig)
    fits = [(entry, window) for artist, entry, window in noted["fits"] if _shown(artist)]
    unique = []
    for entry, _ in fits:  # one entry per (route, label, where): a curve per panel with one legend entry
        if entry not in unique:
            unique.append(entry)
    windows = sorted({tuple(w) for _, w in fits if np.all(np.isfinite(w))})
    title = fig.get_suptitle()
    return {
        "figure": str(name),
        "title": title,
        "references": drawn(fig),
        "fits": unique,
        "window": list(windows[0]) if len(windows) == 1 else None,
        "series": list(noted["series"]),
        "profiles": fig.get_gid() == PROFILES_GID,
        "notes": [k for k in NOTES if k in noted["notes"]],
        "left_out": [k for k in LEFT_OUT if k in noted["left_out"]],
        "unresolved": sorted(int(n) for n in shown_nodes(fig)),
    }


def record_json(record: dict) -> str:
    """``record`` as the text of ``{figure}.record.json``: sorted keys, no timestamp, one trailing newline
    (byte-identical on rerun)."""
    return json.dumps(record, sort_keys=True, indent=1, ensure_ascii=False) + "\n"
