"""The cross-machine comparisons (tests/compare_outputs.py) pass rounding noise and fail real changes."""
import matplotlib.pyplot as plt
import numpy as np
import pytest

from compare_outputs import IMAGE_RMS_TOL, assert_heights_close, assert_images_close, assert_text_close, image_rms

TABLE = "| κ rises | rises | κ(0.05): 2.209 ± 0.010 (k_l=1), 2.397 (k_l=8); 4 of 5 | **reproduced** |\n"


@pytest.mark.parametrize("here, shipped", [(TABLE, TABLE), (TABLE.replace("2.209", "2.210"), TABLE),
                                           (TABLE.replace("0.010", "0.009"), TABLE),
                                           (TABLE.replace("2.397", "2.4"), TABLE.replace("2.397", "2.399"))])
def test_text_passes_a_last_digit_rounded_the_other_way(here, shipped):
    assert_text_close(here, shipped)


@pytest.mark.parametrize("here", [TABLE.replace("2.209", "2.211"), TABLE.replace("reproduced", "partly"),
                                  TABLE.replace("4 of 5", "3 of 5"), TABLE.replace("k_l=8", "k_l=9"),
                                  TABLE + "| extra row |\n", TABLE.replace("2.397", "2.4"),
                                  TABLE.replace("2.209", "2.2")])
def test_text_fails_a_real_change(here):
    with pytest.raises(AssertionError):
        assert_text_close(here, TABLE)


def _figure(path, label, shift=0.0):
    fig, ax = plt.subplots(figsize=(7, 4.4), dpi=300)
    ax.plot([0, 1], [0 + shift, 1], label=label)
    ax.legend(fontsize=7)
    fig.savefig(path)
    plt.close(fig)
    return path


def test_images_pass_the_same_drawing_and_fail_one_changed_digit(tmp_path):
    a = _figure(tmp_path / "a.png", "fit: μ = 0.537")
    assert_images_close(_figure(tmp_path / "b.png", "fit: μ = 0.537"), a)
    changed = _figure(tmp_path / "c.png", "fit: μ = 0.538")
    assert image_rms(changed, a) > 10 * IMAGE_RMS_TOL  # measured 1.68
    with pytest.raises(AssertionError, match="RMS"):
        assert_images_close(changed, a)
    with pytest.raises(AssertionError):
        assert_images_close(_figure(tmp_path / "d.png", "fit: μ = 0.537", shift=0.02), a)


def test_heights_pass_rounding_and_fail_a_change():
    h = np.random.default_rng(0).standard_normal((32, 32))
    assert_heights_close(h * (1 + 1e-12), h)
    with pytest.raises(AssertionError):
        assert_heights_close(h * (1 + 1e-6), h)
    g = h.copy()
    g[0, 0] = np.nan
    with pytest.raises(AssertionError, match="undefined"):
        assert_heights_close(g, h)
