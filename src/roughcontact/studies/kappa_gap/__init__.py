"""The κ gap: how far each candidate cause moves κ(A/A0) at the paper's representative point.

:mod:`.cases` solves one surface of one variant, :mod:`.analysis` pairs the variants and summarises
them, :mod:`.page` writes ``kappa-gap.md`` (``python -m roughcontact.studies.kappa_gap``).
"""

from .analysis import (
    CLOSES_RULE,
    MATERIAL,
    collect,
    fit_kappa,
    kappa_at_areas,
    paper_kappa,
    richardson,
    summarise,
)
from .cases import (
    KAPPA_BGT,
    METHODS,
    ROLES,
    SK_MAX_ITER,
    TARGET_AREAS,
    area_variable,
    case_surface,
    definitions,
    describe,
    solve_case,
)
from .page import (
    COMMANDS,
    SECTIONS,
    conclusion,
    markdown,
    publish,
    regenerate,
)

__all__ = [
    "TARGET_AREAS",
    "KAPPA_BGT",
    "ROLES",
    "METHODS",
    "SK_MAX_ITER",
    "definitions",
    "area_variable",
    "solve_case",
    "describe",
    "case_surface",
    "kappa_at_areas",
    "paper_kappa",
    "fit_kappa",
    "richardson",
    "collect",
    "MATERIAL",
    "CLOSES_RULE",
    "summarise",
    "SECTIONS",
    "COMMANDS",
    "conclusion",
    "markdown",
    "regenerate",
    "publish",
]
