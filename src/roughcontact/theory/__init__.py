"""Exact and analytical references for the contact of rough surfaces: asymptotes, Persson, the CEL, BGT/Greenwood.

Everything here is a pure function of its arguments (no I/O). Conventions follow
:mod:`roughcontact.surfaces.synthetic`: wavenumbers ``k`` are mode numbers in cycles per ``L``
(``k = L / lambda``), angular wavenumbers are ``q = 2 pi k / L``, heights and ``L``
share one length unit ``u``; pressures ``p0`` and the contact modulus ``E*`` share one
pressure unit; ``h'`` is the rms slope ``sqrt(<|grad h|^2>)`` [-]; ``a = A/A0`` is the
real contact-area fraction [-].

Contents
--------
- Small-load asymptotes ``A/A0 = kappa p0 / (h' E*)`` with ``kappa_BGT = sqrt(2 pi)``
  (Bush, Gibson & Thomas 1975, also Greenwood 2006 and Nayak-Thomas in the limit
  ``A/A0 -> 0``) and ``kappa_P = sqrt(8 / pi)`` (Persson 2001).
- Persson's full curve ``A/A0 = erf(sqrt(2) p0 / (E* h'))``.
- The contact evolution law (CEL) of Yastrebov, Anciaux & Molinari (2012), its inverse,
  the effective ``kappa(A/A0)`` it implies and the power law for ``d pbar / d p0``.
- Spectral moments of the ideal isotropic power-law spectrum ``C(k) ~ k^(-2(1+H))`` on
  ``k_l <= |k| <= k_s``: in closed form (continuous integrals) and as the discrete sum
  over the integer modes of an ``n x n`` grid (what :func:`~roughcontact.surfaces.synthetic.generate_surface`
  actually draws), and Nayak's bandwidth ``alpha = m0 m4 / m2^2``.
- The exact periodic full-contact pressure ``p0 + (E*/2) F^-1[|q| h_hat]`` and the load at which the
  last node touches.
- Persson's theory beyond the area for a discrete spectrum: the pressure distribution ``P(p)``, the
  mean interfacial separation ``u(p0)`` (Yang & Persson 2008) and the contact stiffness ``-dp0/du``.

Finite-load BGT and Greenwood curves
------------------------------------
The paper's Fig. 2 (``fig:5`` in its source) compares with the curves of Bush, Gibson & Thomas (1975,
exact elliptic Hertz per summit) and of Greenwood (2006, "simplified elliptic model":
geometric-mean-radius sphere per summit) for ``alpha = 2``, both built on Nayak's (1971)
summit statistics. They live in :mod:`.asperity` (summit statistics in :mod:`.summits`):
:func:`asperity_model` (``A/A0`` and ``pbar = p0/(E* h')`` at a reduced separation
``xi_d = d/sqrt(m0)``), :func:`asperity_reduced_area` / :func:`asperity_reduced_pressure`
(one at given other), :func:`asperity_area` (dimensional, like :func:`persson_area`),
:func:`asperity_kappa`, the summit statistics :func:`nayak_summit_pdf`,
:func:`nayak_summit_pdf_xi_t`, :func:`nayak_summit_density` and the elliptic Hertz factors
:func:`hertz_elliptic_factors`. Their small-load limit is :data:`KAPPA_BGT`, reached only
slowly (``1 - kappa/sqrt(2 pi) ~ c alpha / xi_d^2``).

Modules: :mod:`.laws` (asymptotes, Persson, CEL), :mod:`.spectra` (spectral moments, Nayak's alpha),
:mod:`.summits` and :mod:`.asperity` (finite-load asperity theories), :mod:`.perimeter` (the perimeter
correction of a pixel-counted area), :mod:`.full_contact` (the exact periodic full-contact solution),
:mod:`.persson` (Persson's pressure distribution, mean gap and stiffness).
"""

from .asperity import (
    XI_D_RANGE,
    asperity_area,
    asperity_kappa,
    asperity_max_load,
    asperity_model,
    asperity_reduced_area,
    asperity_reduced_pressure,
)
from .full_contact import (
    full_contact_load,
    full_contact_pressure,
    wavenumbers,
)
from .laws import (
    KAPPA_BGT,
    KAPPA_PERSSON,
    cel_area,
    cel_area_limit,
    cel_dpbar_dp0,
    cel_kappa,
    cel_pressure,
    linear_area,
    persson_area,
)
from .perimeter import (
    PERIMETER_C,
    perimeter_corrected_area,
)
from .persson import (
    W_RULES,
    mode_spectrum,
    mode_weights,
    persson_j,
    persson_mean_gap,
    persson_mean_gap_terms,
    persson_pressure_distribution,
    persson_stiffness,
    persson_stiffness_terms,
    power_law_terms,
)
from .spectra import (
    areal_moments,
    discrete_power_law_moments,
    nayak_alpha,
    power_law_alpha,
    power_law_moments,
)
from .summits import (
    ASPERITY_MODELS,
    NAYAK_ALPHA_MIN,
    hertz_elliptic_factors,
    nayak_summit_density,
    nayak_summit_pdf,
    nayak_summit_pdf_xi_t,
)

__all__ = [
    "KAPPA_BGT",
    "KAPPA_PERSSON",
    "linear_area",
    "persson_area",
    "cel_area",
    "cel_pressure",
    "cel_area_limit",
    "cel_kappa",
    "cel_dpbar_dp0",
    "power_law_moments",
    "discrete_power_law_moments",
    "nayak_alpha",
    "areal_moments",
    "power_law_alpha",
    "NAYAK_ALPHA_MIN",
    "ASPERITY_MODELS",
    "nayak_summit_density",
    "nayak_summit_pdf",
    "nayak_summit_pdf_xi_t",
    "hertz_elliptic_factors",
    "XI_D_RANGE",
    "asperity_model",
    "asperity_reduced_area",
    "asperity_reduced_pressure",
    "asperity_max_load",
    "asperity_area",
    "asperity_kappa",
    "PERIMETER_C",
    "perimeter_corrected_area",
    "wavenumbers",
    "full_contact_pressure",
    "full_contact_load",
    "mode_spectrum",
    "persson_pressure_distribution",
    "persson_j",
    "persson_mean_gap",
    "persson_stiffness",
    "W_RULES",
    "mode_weights",
    "power_law_terms",
    "persson_mean_gap_terms",
    "persson_stiffness_terms",
]
