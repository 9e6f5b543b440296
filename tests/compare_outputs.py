"""Comparing what this machine computes with what another machine computed and shipped.

Floating-point results are not bit-identical across CPUs: numpy and FFTW take other vectorised
paths with AVX-512 than with AVX2 or on ARM, and round differently in the last bits (measured:
10441 of 16384 generated heights differ, by at most 1e-11 relative; a published figure
differs in 124 antialiased pixels by at most 2 of 255). Byte identity is a promise for reruns
on the same machine (tests/test_workflow.py, test_interrupt.py, test_determinism.py); a test that
compares against a file made elsewhere (published figures and claim tables, the README's
figures, shipped example files) uses these helpers, each with a tolerance stated and justified
below.
"""
from __future__ import annotations

import re
from decimal import Decimal
from pathlib import Path

import numpy as np
from matplotlib.testing.compare import calculate_rms
from PIL import Image

#: Largest RMS difference (0-255 pixel values, over all pixels and RGB channels) accepted between
#: a figure drawn here and the shipped one. Rendering noise across CPUs measured 0.0065-0.0066
#: (docs/reproduction's dpbar.png, 2100 x 1320 px, AVX-512 against not); one changed digit in a
#: 7-pt legend of a figure that size is 1.3-1.7: the tolerance is 15x the noise and 13x below a
#: changed digit, so a stale label, a moved point or a missing curve still fails.
IMAGE_RMS_TOL = 0.1

NUMBER = re.compile(r"(?<![\w.])[-+−]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?(?![\w])")


def image_rms(actual: Path, expected: Path) -> float:
    """RMS difference of two PNG files in 0-255 units; ``inf`` when their sizes differ."""
    a = np.asarray(Image.open(actual).convert("RGB"), dtype=float)
    b = np.asarray(Image.open(expected).convert("RGB"), dtype=float)
    return float("inf") if a.shape != b.shape else float(calculate_rms(a, b))


def assert_images_close(actual: Path, expected: Path, tol: float = IMAGE_RMS_TOL) -> None:
    """Fail unless the two PNGs have one size and differ by at most ``tol`` RMS (see IMAGE_RMS_TOL)."""
    rms = image_rms(actual, expected)
    assert rms <= tol, (f"{actual.name}: drawn here it differs from {expected} by RMS {rms:.3g} "
                        f"(tolerance {tol}: rendering noise across machines is below 0.01)")


def _numbers(text: str) -> tuple[str, list[str]]:
    """``text`` with every number replaced by ``#``, and the numbers as written."""
    found = [m.group(0) for m in NUMBER.finditer(text)]
    return NUMBER.sub("#", text), found


def _one_printed_unit(a: str, b: str) -> bool:
    """Whether two printed numbers differ by at most one unit of their last printed decimal.

    A number computed here and one computed elsewhere, each rounded to the digits printed, can
    differ by one unit in the last digit when the exact values straddle a rounding boundary.
    The unit is the finer of the two (``%g`` drops trailing zeros: 2.39949 prints 2.399, 2.3995
    prints 2.4). Integers (counts, grid labels) carry no rounding and must be equal.
    """
    da, db = (Decimal(s.replace("−", "-")) for s in (a, b))
    if "." not in a + b and "e" not in (a + b).lower():
        return da == db
    unit = min(Decimal(1).scaleb(da.as_tuple().exponent), Decimal(1).scaleb(db.as_tuple().exponent))
    return abs(da - db) <= unit


def assert_text_close(actual: str, expected: str, where: str = "") -> None:
    """Fail unless two texts are equal apart from printed decimals one last-digit unit apart.

    Words, verdicts, layout and integers must match exactly; see :func:`_one_printed_unit`.
    """
    for n, (la, le) in enumerate(zip(actual.splitlines(), expected.splitlines(), strict=False), 1):
        (sa, na), (se, ne) = _numbers(la), _numbers(le)
        assert sa == se and len(na) == len(ne), f"{where} line {n} differs:\n  here:    {la}\n  shipped: {le}"
        bad = [(x, y) for x, y in zip(na, ne, strict=True) if not _one_printed_unit(x, y)]
        assert not bad, f"{where} line {n}: numbers {bad} (here, shipped) differ by more than their last digit"
    assert len(actual.splitlines()) == len(expected.splitlines()), f"{where}: line counts differ"


def assert_heights_close(actual: np.ndarray, expected: np.ndarray, what: str = "") -> None:
    """Heights equal up to FFT rounding: ``atol = 1e-9 * rms``, everything else (shape, NaN mask) exact.

    Surfaces are FFT-filtered white noise: each height carries rounding of order
    ``eps log2(N)`` times the rms (1e-14 at N = 256); 1e-9 leaves room for text formats that
    print 12 significant digits and still fails on any change of a surface's parameters.
    """
    assert actual.shape == expected.shape, f"{what}: shape {actual.shape} here, {expected.shape} shipped"
    np.testing.assert_array_equal(np.isnan(actual), np.isnan(expected), err_msg=f"{what}: undefined points")
    scale = float(np.sqrt(np.nanmean(np.square(expected - np.nanmean(expected)))))
    np.testing.assert_allclose(actual, expected, rtol=0, atol=1e-9 * scale, err_msg=what)
