"""The paper's claims measured on a run: numbers, verdicts and figures for docs/reproduction/.

:mod:`.claims` measures the claims (pure functions over the aggregates), :mod:`.page` publishes a run
and regenerates the page (``python -m roughcontact.studies.reproduction``).
"""

from .claims import (
    H_DIRECTION_CLAIM,
    KAPPA_AREA,
    KAPPA_AREAS,
    KAPPA_CLAIMS,
    NOISE_DRAWS,
    NOISE_SEED,
    PAPER_CEL,
    PAPER_KAPPA,
    SYMBOL,
    cel_claims,
    claims,
    figure5_claims,
    kappa_at,
    kappa_claims,
    noise_floor,
    representativity_claims,
)
from .page import (
    DATA_FILES,
    markdown_table,
    publish,
    regenerate,
)

__all__ = [
    "PAPER_KAPPA",
    "PAPER_CEL",
    "KAPPA_AREAS",
    "KAPPA_AREA",
    "kappa_at",
    "NOISE_DRAWS",
    "NOISE_SEED",
    "noise_floor",
    "representativity_claims",
    "KAPPA_CLAIMS",
    "kappa_claims",
    "H_DIRECTION_CLAIM",
    "SYMBOL",
    "cel_claims",
    "figure5_claims",
    "claims",
    "DATA_FILES",
    "markdown_table",
    "regenerate",
    "publish",
]
