"""The README's figures are what `make run` draws now (within rendering noise across machines)."""
import re

import pytest

from compare_outputs import assert_images_close
from conftest import REPO

#: ``![alt](docs/figures/demo_NAME.png)``: the demo scene's figure NAME, as results/demo/figures/NAME.png.
README_FIGURE = re.compile(r"!\[[^\]]*\]\((docs/figures/demo_(\w+)\.png)\)")


def test_the_readme_shows_demo_figures():
    shown = README_FIGURE.findall((REPO / "README.md").read_text())
    assert {name for _, name in shown} >= {"representativity", "area_load", "kappa", "dpbar"}, shown


@pytest.mark.slow
def test_readme_figures_match_what_make_run_draws(demo_run):
    # `make run` runs the demo scene; demo_run is that run. A stale README figure (an old legend,
    # an old colour) fails; regenerate with `make run` and copy results/demo/figures/NAME.png
    # to docs/figures/demo_NAME.png.
    for path, name in README_FIGURE.findall((REPO / "README.md").read_text()):
        assert_images_close(demo_run / "results" / "demo" / "figures" / f"{name}.png", REPO / path)
