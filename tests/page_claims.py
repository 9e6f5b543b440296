"""A page's words against its claim table: every claim its prose makes is tied to a row and holds there.

Written apart from the code that makes the table (issue 61): it reads the page's Markdown and the
table's text only. A claim phrase in the prose (:data:`PHRASES`) must be followed, before the next
claim phrase, by a tie ``<!-- check ROW[ from "A"][ to "B"]: KIND -->`` (an HTML comment, unseen
on the rendered page). ``ROW`` is the start of a row's question (``Q4a``); the row's ``measured``
text between the first ``A`` and the next ``B`` after it (default: all of it) holds the numbers;
``KIND`` says which of them the claim is about:

- ``ratios``: the values printed before a band, ``v [low, high]``;
- ``band edges``: the bands' ``low`` and ``high``;
- ``values``: every number that is not a label's (not right after ``=``);
- ``percent``: the numbers printed with ``%``;
- ``curvature above``: the curvature of the fit above the bend (``α ≥ …: … curvature = c ± e``);
- ``quote "TEXT"``: the row prints ``TEXT``, and every number of the claim phrase is in it.

The phrases and what they claim of the numbers ``v``:

- ``within X %``: every ``|v − 1| ≤ X/100`` (``percent``: ``|v| ≤ X``);
- ``within a–b``, ``between a and b``: every ``v``, rounded as ``a`` and ``b`` are, lies in ``[a, b]``;
- ``spans a–b``: the smallest ``v`` rounds to ``a`` and the largest to ``b``;
- ``flattens``, ``saturates``, ``levels off``, ``plateau``: the fall bends where the claim is
  made, i.e. ``curvature above`` is positive by more than 2 standard errors.
"""

from __future__ import annotations

import re

NUMBER = r"[-+−]?\d+(?:\.\d+)?"
_RANGE = rf"({NUMBER})\s*[–-]\s*({NUMBER})"

#: Claim phrases: name, pattern (its groups are the claim's numbers).
PHRASES = (
    ("within %", re.compile(rf"\bwithin ({NUMBER}) %")),
    ("within range", re.compile(rf"\bwithin {_RANGE}")),
    ("between", re.compile(rf"\bbetween ({NUMBER}) and ({NUMBER})")),
    ("spans", re.compile(rf"\bspans? {_RANGE}")),
    ("bends", re.compile(r"\b(?:flatten\w*|saturat\w*|levels? off|plateau\w*)", re.IGNORECASE)),
)

_TIE = re.compile(r"<!--\s*check\s+(?P<row>Q\w+)(?:\s+from\s+\"(?P<start>[^\"]+)\")?(?:\s+to\s+\"(?P<stop>[^\"]+)\")?"
                  r"\s*:\s*(?P<kind>[^>]*?)\s*-->")


def _num(text: str) -> float:
    return float(text.replace("−", "-"))


def _decimals(text: str) -> int:
    return len(text.split(".")[1]) if "." in text else 0


def prose(markdown: str) -> list[str]:
    """The paragraphs of ``markdown`` that are prose: no table lines, no headings, one line each."""
    out = []
    for block in re.split(r"\n\s*\n", markdown):
        lines = [ln for ln in block.splitlines()
                 if not (ln.lstrip().startswith("|") and ln.rstrip().endswith("|")) and not ln.startswith("#")]
        if lines:
            out.append(" ".join(" ".join(lines).split()))
    return out


def rows(table: str) -> dict[str, str]:
    """``{question: measured}`` of a claim table's Markdown (question, comparison, measured, verdict, rule)."""
    out = {}
    for line in table.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split(" | ")]
        if len(cells) == 5 and cells[0] not in ("question", "---"):
            out[cells[0]] = cells[2]
    return out


def _span(measured: str, start: str | None, stop: str | None) -> str | None:
    i = 0 if start is None else measured.find(start)
    if i < 0:
        return None
    j = len(measured) if stop is None else measured.find(stop, i + len(start or ""))
    return measured[i:j if j >= 0 else len(measured)]


def _numbers(span: str, kind: str) -> list[float]:
    if kind == "ratios":
        return [_num(v) for v, _, _ in re.findall(rf"({NUMBER}) \[({NUMBER}), ({NUMBER})\]", span)]
    if kind == "band edges":
        return [_num(v) for pair in re.findall(rf"\[({NUMBER}), ({NUMBER})\]", span) for v in pair]
    if kind == "percent":
        return [_num(v) for v in re.findall(rf"({NUMBER}) %", span)]
    if kind == "values":
        return [_num(m.group(0)) for m in re.finditer(NUMBER, span)
                if not re.search(r"[=/]\s?$", span[:m.start()]) and not span[max(0, m.start() - 1):m.start()].isalnum()
                and span[m.start() - 1:m.start()] != "_"]
    raise ValueError(f"unknown kind {kind!r}")


def _holds(phrase: str, groups: tuple[str, ...], tie: re.Match, measured: str) -> str | None:
    """None when the claim holds against its row, else why not."""
    kind = tie["kind"]
    span = _span(measured, tie["start"], tie["stop"])
    if span is None:
        return f"the row does not print {tie['start']!r}"
    if kind.startswith("quote"):
        quoted = re.fullmatch(r'quote\s+"([^"]+)"', kind)
        if quoted is None or quoted[1] not in span:
            return f"the row does not print {kind[5:].strip()}"
        missing = [g for g in groups if g.replace("−", "-") not in quoted[1].replace("−", "-")]
        return f"{', '.join(missing)} not in the quoted {quoted[1]!r}" if missing else None
    if phrase == "bends":
        if kind != "curvature above":
            return "a bend is claimed of something other than 'curvature above'"
        fits = re.findall(rf"α ≥ {NUMBER}[^;]*?curvature = ({NUMBER}) ± ({NUMBER})", span)
        if not fits:
            return "the row prints no fit above the bend (α ≥ …: curvature = c ± e)"
        bad = [f"{c} ± {e}" for c, e in fits if not _num(c) > 2 * _num(e)]
        return f"the curvature above the bend is within 2 standard errors of zero: {', '.join(bad)}" if bad else None
    values = _numbers(span, kind)
    if not values:
        return f"no {kind} in the row's span"
    if phrase == "within %":
        x = _num(groups[0])
        off = [v for v in values if (abs(v) if kind == "percent" else abs(v - 1) * 100) > x + 1e-9]
        return f"{', '.join(f'{v:g}' for v in off)} not within {groups[0]} %" if off else None
    lo, hi = (_num(g) for g in groups)
    digits = max(_decimals(g) for g in groups)
    r = [round(v, digits) for v in values]
    if phrase == "spans":
        return None if (min(r) == lo and max(r) == hi) else f"the values span {min(values):g}–{max(values):g}"
    out = [v for v, rv in zip(values, r, strict=True) if not lo <= rv <= hi]
    return f"{', '.join(f'{v:g}' for v in out)} outside {groups[0]}–{groups[1]}" if out else None


def check(markdown: str, table: str) -> list[str]:
    """Every claim phrase of ``markdown``'s prose without a tie, or whose tie's numbers contradict it."""
    by_row = rows(table)
    problems = []
    for para in prose(markdown):
        bare = re.sub(r"<!--.*?-->", lambda m: " " * len(m.group(0)), para)  # no phrase inside a tie
        hits = sorted(((m.start(), m.end(), name, m.groups()) for name, pat in PHRASES for m in pat.finditer(bare)))
        for i, (start, end, name, groups) in enumerate(hits):
            limit = hits[i + 1][0] if i + 1 < len(hits) else len(para)
            tie = _TIE.search(para, end, limit)
            where = para[max(0, start - 60):end + 20]
            if tie is None:
                problems.append(f"untied claim {para[start:end]!r} in …{where}…")
                continue
            matches = [q for q in by_row if q.split(":")[0] == tie["row"]]
            if len(matches) != 1:
                problems.append(f"{tie['row']}: no such row (or several) for {para[start:end]!r}")
                continue
            why = _holds(name, groups, tie, by_row[matches[0]])
            if why:
                problems.append(f"{para[start:end]!r} ({tie['row']}): {why}, in …{where}…")
    return problems
