"""Figures build from contract-format data and save byte-identically."""

import os
import subprocess
import sys
import textwrap

import matplotlib.colors as mcolors
import numpy as np
import pytest
import xarray as xr
from matplotlib.figure import Figure

import figure_builders
from cel_synthetic import simulate_cel_cases
from roughcontact.analysis.aggregate.derived import aggregate_contact
from roughcontact.analysis.aggregate.seeds import seed_statistics
from roughcontact.figures.area_load import fig_area_load
from roughcontact.figures.dpbar import fig_dpbar
from roughcontact.figures.kappa import fig_kappa
from roughcontact.figures.representativity import fig_representativity, fig_surface_examples
from roughcontact.figures.style import DOUBLE_COLUMN_IN, OKABE_ITO, save_figure
from roughcontact.surfaces.synthetic import generate_surface


@pytest.fixture(scope="module")
def contact():
    return figure_builders.contact()


@pytest.fixture(scope="module")
def rep_stats():
    return figure_builders.rep_stats()


@pytest.fixture(scope="module")
def examples():
    return [(generate_surface(64, kl, 32, 0.8, 0, rms_height=0.1), f"$k_l = {kl}$") for kl in (1, 4, 16)]


def _builders(contact, rep_stats, examples):
    agg, stats, fit = contact
    return {
        "representativity": lambda: fig_representativity(rep_stats),
        "surface_examples": lambda: fig_surface_examples(examples),
        "area_load": lambda: fig_area_load(agg, stats, fit),
        "kappa": lambda: fig_kappa(agg, stats, fit),
        "dpbar": lambda: fig_dpbar(agg, stats, fit),
        "area_load_nofit": lambda: fig_area_load(agg, stats),
        "kappa_one_panel": lambda: fig_kappa(agg, stats, fit, k_s=[32.0], hurst=[0.84]),
    }


@pytest.mark.parametrize("name", ["representativity", "surface_examples", "area_load", "kappa", "dpbar",
                                  "area_load_nofit", "kappa_one_panel"])
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_figure_builds_and_saves_byte_identically(name, contact, rep_stats, examples, tmp_path):
    build = _builders(contact, rep_stats, examples)[name]
    fig = build()
    assert isinstance(fig, Figure)
    assert fig.get_size_inches()[0] <= DOUBLE_COLUMN_IN + 0.01
    first = save_figure(fig, tmp_path / "a" / name)
    second = save_figure(build(), tmp_path / "b" / f"{name}.pdf")  # a fresh render, suffix form
    assert [p.suffix for p in first] == [".png", ".pdf"]
    assert first[0].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and first[1].read_bytes()[:5] == b"%PDF-"
    for a, b in zip(first, second, strict=True):
        assert a.read_bytes() == b.read_bytes(), a.name
    for ax in fig.axes:
        if ax.get_visible() and ax.has_data() and not ax.get_label() == "<colorbar>":
            assert ax.get_xlabel(), name
    assert fig.legends, "legend expected outside the axes"


def test_labels_symbols_and_units(contact):
    agg, stats, fit = contact
    ax = fig_area_load(agg, stats, fit).axes[0]
    assert ax.get_xlabel() == r"$p_0/E^*$ [1]" and ax.get_ylabel() == r"$A/A_0$ [1]"
    ax = fig_kappa(agg, stats, fit).axes[0]
    assert "kappa" in ax.get_ylabel() and "[1]" in ax.get_ylabel()
    ax = fig_dpbar(agg, stats, fit).axes[0]
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    assert r"\partial\bar p/\partial p_0" in ax.get_ylabel()


def test_legend_lies_outside_the_axes(contact):
    agg, stats, fit = contact
    fig = fig_kappa(agg, stats, fit)
    fig.draw_without_rendering()
    legend = fig.legends[0].get_window_extent()
    for ax in fig.axes:
        if ax.get_visible():
            assert not legend.overlaps(ax.get_window_extent())


def test_data_colours_are_okabe_ito(contact):
    agg, stats, fit = contact
    fig = fig_area_load(agg, stats, fit)
    allowed = {mcolors.to_hex(c) for c in OKABE_ITO}
    for line in fig.axes[0].get_lines():
        c = mcolors.to_rgb(line.get_color())
        grey = np.allclose(c, c[0])
        assert grey or mcolors.to_hex(c) in allowed, c


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_save_is_reproducible_across_processes(tmp_path):
    script = textwrap.dedent("""
        import sys
        from cel_synthetic import simulate_cel_cases  # tests/ is the working directory
        from roughcontact.analysis.aggregate import aggregate_contact, seed_statistics
        from roughcontact.analysis.fit import fit_cel
        from roughcontact.figures.area_load import fig_area_load
        from roughcontact.figures.style import save_figure
        dss, names = simulate_cel_cases(hurst=(0.36, 0.84), seeds=range(3), point_noise=1e-4)
        agg = aggregate_contact(dss, names)
        save_figure(fig_area_load(agg, seed_statistics(agg), fit_cel(agg, n_boot=10)), sys.argv[1])
    """)
    outs = []
    for salt in ("1", "12345"):
        env = dict(os.environ, PYTHONHASHSEED=salt)
        base = tmp_path / salt / "fig"
        subprocess.run([sys.executable, "-c", script, str(base)], check=True, env=env, timeout=300,
                       cwd=os.path.dirname(os.path.abspath(__file__)))
        outs.append([base.with_suffix(".png").read_bytes(), base.with_suffix(".pdf").read_bytes()])
    assert outs[0] == outs[1]


def test_bad_inputs_are_rejected(contact, rep_stats, examples, tmp_path):
    agg, stats, fit = contact
    with pytest.raises(ValueError, match="k_s"):
        fig_kappa(agg, stats, fit, k_s=[64.0])
    with pytest.raises(ValueError, match="estimator"):
        fig_dpbar(agg, stats, fit, estimator="median")
    with pytest.raises(ValueError, match="e_star"):
        fig_area_load(agg.drop_attrs(), stats)
    with pytest.raises(ValueError, match="stats lacks"):
        fig_dpbar(agg, stats.drop_vars("dpbar_dp0_mean"))
    two_h = xr.concat([rep_stats, rep_stats.assign_coords(H=[0.5])], dim="H")
    with pytest.raises(ValueError, match="hurst"):
        fig_representativity(two_h)
    fig_representativity(two_h, hurst=0.5)
    with pytest.raises(ValueError, match="square"):
        fig_surface_examples([(np.zeros((4, 5)), "x")])
    with pytest.raises(ValueError, match="1 to 6"):
        fig_surface_examples([])
    with pytest.raises(ValueError, match="Figure"):
        save_figure("not a figure", tmp_path / "x")


def test_finite_load_asperity_curves_are_drawn_and_labelled(contact):
    """BGT and Greenwood (2006) at the paper's alpha = 2 and, for one bandwidth, at the surfaces' own alpha."""
    from roughcontact.theory.asperity import asperity_kappa

    agg, stats, fit = contact
    one = {"k_l": [16.0], "k_s": [32.0]}  # one family: its surfaces share one alpha
    for draw in (fig_area_load, fig_kappa):
        fig = draw(agg.sel(one), stats.sel(one), fit.sel(one))
        labels = [t.get_text() for t in fig.legends[0].get_texts()]
        alpha = float(agg["alpha"].sel(one).mean())
        for name in ("BGT", "Greenwood (2006)"):
            assert f"{name}, $\\alpha = 2$ (paper)" in labels, labels
            assert f"{name}, $\\alpha = {alpha:.2f}$ (these surfaces)" in labels, labels
        # k_l = 4, 16 and k_s = 32, 128 together: no single "these surfaces" curve describes them all
        labels = [t.get_text() for t in draw(agg, stats, fit).legends[0].get_texts()]
        assert not any("these surfaces" in lab for lab in labels), labels
    ax = fig_kappa(agg, stats, fit).axes[0]
    drawn = [line.get_ydata() for line in ax.get_lines() if len(line.get_ydata()) == 120]
    a = np.linspace(0, float(stats["area_fraction_mean"].max()), 120)
    assert any(np.allclose(y, asperity_kappa(a, alpha=2.0, model="bgt")) for y in drawn)


def test_kappa_figure_names_paper_and_run_curves(contact):
    """The paper's own CEL and this run's fit are both drawn and told apart; the window has an entry."""
    from roughcontact.figures.load_curves import PAPER_CONSTANTS
    from roughcontact.theory.laws import cel_kappa

    agg, stats, fit = contact
    fig = fig_kappa(agg, stats, fit)
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert any(lab.startswith("CEL, paper: ") and "1.145" in lab for lab in labels), labels
    assert any(lab.startswith("CEL fitted (paper's route)") for lab in labels), labels
    assert any(lab.startswith("fit window") for lab in labels) and any("Persson" in lab for lab in labels)
    ax = fig.axes[0]
    a = np.linspace(0, float(stats["area_fraction_mean"].sel(k_s=32.0).max()), 200)
    assert any(len(line.get_ydata()) == 200 and np.allclose(line.get_ydata(), cel_kappa(a, **PAPER_CONSTANTS))
               for line in ax.get_lines())


def _fit_law_labels(agg, stats, fit, **kw):
    """The legend texts of this run's fitted power law in fig_dpbar, one per k_s panel."""
    return [t.get_text() for t in fig_dpbar(agg, stats, fit, **kw).legends[0].get_texts()
            if t.get_text().startswith("fitted (")]


def _at_interval(fit, constant, k_s=32.0, estimator="paper"):
    """A constant of the pooled k_l = 16 group, rounded to its interval (the legend's rule, issue 60)."""
    from roughcontact.figures.style import at_interval

    sel = {"k_l": 16.0, "k_s": k_s, "H_group": "pooled", "estimator": estimator, "constant": constant}
    return at_interval(*(float(fit[v].sel(sel)) for v in ("value", "ci_low", "ci_high")))


def _loosen(fit, constants, k_s=32.0, estimator="paper"):
    """``fit`` with ``constants`` of the pooled k_l = 16 group at ``k_s`` flagged as not constrained."""
    out = fit.copy(deep=True)
    for c in constants:
        out["constrained"].loc[{"k_l": 16.0, "k_s": k_s, "H_group": "pooled", "estimator": estimator,
                                "constant": c}] = 0
    return out


def test_dpbar_legend_labels_each_constant_for_what_it_is(contact):
    """Issue 24: each of mu and beta is printed when the data constrain it and called "not constrained
    by the data" when they do not (an interval wider than the value is no number), never both for one."""
    agg, stats, fit = contact
    head = r"fitted (paper's route), $\lambda_l = L/16$, $\lambda_s = L/32$: "
    mu, beta = _at_interval(fit, "mu"), _at_interval(fit, "beta")
    assert fit["constrained"].sel(k_l=16.0, H_group="pooled", estimator="paper").all()
    both, other = _fit_law_labels(agg, stats, fit)
    assert both == head + rf"$\beta$ = {beta}, $\mu$ = {mu}", both
    assert "128" in other and "$\\beta$ = " in other and "$\\mu$ = " in other
    # mu constrained, beta not: mu's value, and beta named as not constrained; the other panel as it was
    first, second = _fit_law_labels(agg, stats, _loosen(fit, ["beta"]))
    assert first == head + rf"$\mu$ = {mu}, $\beta$ not constrained by the data", first
    assert second == other
    first, _ = _fit_law_labels(agg, stats, _loosen(fit, ["mu"]))
    assert first == head + rf"$\beta$ = {beta}, $\mu$ not constrained by the data", first
    first, _ = _fit_law_labels(agg, stats, _loosen(fit, ["mu", "beta"]))
    assert first == head + r"$\beta$, $\mu$ not constrained by the data", first
    # kappa alone unconstrained leaves this figure's mu and beta as they are
    assert _fit_law_labels(agg, stats, _loosen(fit, ["kappa"])) == [both, other]


def test_a_constant_on_a_bound_of_the_joint_fit_is_not_constrained(contact):
    """A joint-fit constant sitting on its bound has a bootstrap interval of nothing (every draw on the
    bound): flagged constrained by the interval rule, yet the data do not constrain it."""
    from roughcontact.analysis.fit.estimators import JOINT_LOWER

    agg, stats, fit = contact
    sel = {"k_l": 16.0, "k_s": 32.0, "H_group": "pooled", "estimator": "joint", "constant": "mu"}
    on_bound = fit.copy(deep=True)
    for var in ("value", "ci_low", "ci_high"):
        on_bound[var].loc[sel] = JOINT_LOWER[1]
    assert int(on_bound["constrained"].sel(sel)) == 1
    first, _ = _fit_law_labels(agg, stats, on_bound, estimator="joint")
    assert first.endswith(r"$\mu$ not constrained by the data") and r"$\beta$ = " in first, first
    first, _ = _fit_law_labels(agg, stats, fit, estimator="joint")
    assert r"$\mu$ = " in first and "not constrained" not in first, first
    labels = [t.get_text() for t in fig_kappa(agg, stats, on_bound, estimator="joint").legends[0].get_texts()]
    assert any(lab.startswith("CEL fitted (joint least squares)") and lab.endswith(r"not constrained by the data at "
                                                                       r"$\lambda_s = L/32$") for lab in labels)


def test_representativity_units_are_mathtext(rep_stats):
    """epsilon's unit appears as mathtext: its number's unit (units "1" for lengths in a reference unit, as the
    pipeline writes it, roughcontact.statistics.representativity.epsilon_attrs), or the "um^(-1/2)" of older files."""
    rep = rep_stats.copy()
    rep["epsilon_mean"].attrs.update(units="1", reference_length_units="um", reference_length_power="-1/2")
    label = fig_representativity(rep).axes[0].get_ylabel()
    assert "^(" not in label and r"$\mathrm{\mu m}^{-1/2}$" in label, label
    rep["epsilon_mean"].attrs.update(reference_length_units="1")  # nondimensional heights
    assert fig_representativity(rep).axes[0].get_ylabel().endswith("[1]")
    rep["epsilon_mean"].attrs = {"units": "um^(-1/2)", "long_name": "files of older versions"}
    label = fig_representativity(rep).axes[0].get_ylabel()
    assert "^(" not in label and r"$\mathrm{\mu m}^{-1/2}$" in label, label
    rep["epsilon_mean"].attrs["units"] = "length unit^-1/2"  # files of older versions
    label = fig_representativity(rep).axes[0].get_ylabel()
    assert "^-1/2" not in label and r"$(\mathrm{length\ unit})^{-1/2}$" in label, label


def test_surface_examples_share_one_scale_by_default():
    rng = np.random.default_rng(1)
    small, large = 0.01 * rng.standard_normal((16, 16)), rng.standard_normal((16, 16))
    fig = fig_surface_examples([(small, "a"), (large, "b")])
    images = [ax.get_images()[0] for ax in fig.axes if ax.get_images()]
    assert len(images) == 2 and images[0].get_clim() == images[1].get_clim() == (large.min(), large.max())
    own = fig_surface_examples([(small, "a"), (large, "b")], shared_scale=False)
    images = [ax.get_images()[0] for ax in own.axes if ax.get_images()]
    assert images[0].get_clim() == (small.min(), small.max())


def test_contact_figures_state_grid_seeds_and_loads(contact):
    import json

    agg, stats, fit = contact
    agg = agg.assign_attrs(scene_parameters=json.dumps({"surface": {"N": 256}}))
    for draw in (fig_area_load, fig_kappa, fig_dpbar):
        title = draw(agg, stats, fit).get_suptitle()
        # 3 seeds per curve, 2 values of H: the 6 surfaces an H-pooled fit (and the result line) counts (issue 60)
        assert "$N = 256$" in title and r"3 seeds $\times$ 2 values of $H$" in title and "$p_0/E^*$ = " in title, \
            (draw.__name__, title)
        one_h = draw(agg.sel(H=[0.84]), stats.sel(H=[0.84]), fit).get_suptitle()
        assert "3 seeds" in one_h and "values of $H$" not in one_h, one_h


# ------------------------------------------------------------ issue 12: readability
def _errorbar_ends(ax):
    """(y, lower end, upper end) of every errorbar container of ``ax`` with vertical bars."""
    out = []
    for cont in ax.containers:
        line, _caps, (bars, *_) = cont.lines[0], cont.lines[1], cont.lines[2]
        segs = bars.get_segments()
        y = np.asarray(line.get_ydata(), dtype=float)
        if len(segs) == len(y):
            out.append((y, np.array([s[:, 1].min() for s in segs]), np.array([s[:, 1].max() for s in segs])))
    return out


def test_dpbar_bars_are_symmetric_in_log_space_and_the_axis_stays_near_the_data(contact):
    """Bars y e^(+-s/y): always above zero and symmetric on the log axis (not y - s clipped near 0)."""
    agg, stats, fit = contact
    agg = agg.copy()
    rng = np.random.default_rng(0)  # noisy loads: s.e.m. comparable to the value in some windows
    agg["mean_contact_pressure"] = agg["mean_contact_pressure"] * (1 + 0.002 * rng.standard_normal(
        agg["mean_contact_pressure"].shape))
    fig = fig_dpbar(agg, stats, fit)
    ax = fig.axes[0]
    ends = _errorbar_ends(ax)
    assert ends, "windowed estimates with error bars expected"
    for y, lo, hi in ends:
        assert np.all(lo > 0)
        np.testing.assert_allclose(np.log(y) - np.log(lo), np.log(hi) - np.log(y), rtol=1e-9, atol=1e-12)
    y_all = np.concatenate([y for y, _, _ in ends])
    assert ax.get_ylim()[0] > y_all.min() / 10, ax.get_ylim()
    assert "log space" in fig.legends[0].get_title().get_text()


def test_dpbar_draws_windowed_slopes_over_faint_finite_differences(contact):
    agg, stats, fit = contact
    fig = fig_dpbar(agg, stats, fit)
    ax = fig.axes[0]
    faint = [ln for ln in ax.get_lines() if ln.get_linestyle() == "None" and (ln.get_alpha() or 1) < 0.5]
    bold = [c.lines[0] for c in ax.containers]
    assert faint and bold
    assert max(ln.get_markersize() for ln in faint) < min(ln.get_markersize() for ln in bold)
    # The raw points are the stored finite differences; the windowed ones are fewer (one per window).
    s = stats.sel(k_l=4.0, k_s=32.0, H=0.36)
    raw = s["dpbar_dp0_mean"].values
    assert any(ln.get_ydata().size == raw.size and np.allclose(ln.get_ydata(), raw) for ln in faint)
    assert all(ln.get_ydata().size < raw.size / 2 for ln in bold)
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert any(lab.startswith("least-squares slope") for lab in labels)
    assert any(lab.startswith("pointwise finite differences (faint)") for lab in labels), labels


def test_dpbar_paper_and_fit_lines_are_told_apart(contact):
    """The paper's power law and the fit differ in colour, dash and width; the legend gives both constants."""
    from roughcontact.figures.load_curves import PAPER_CONSTANTS, fit_constants
    from roughcontact.theory.laws import cel_dpbar_dp0

    agg, stats, fit = contact
    fig = fig_dpbar(agg, stats, fit, k_s=[32.0])
    ax = fig.axes[0]
    consts = fit_constants(fit, 16.0, 32.0, "paper")
    paper = fitted = None
    for ln in ax.get_lines():
        x, y = np.asarray(ln.get_xdata()), np.asarray(ln.get_ydata())
        if x.size != 100:
            continue
        if np.allclose(y, cel_dpbar_dp0(x, mu=PAPER_CONSTANTS["mu"], beta=PAPER_CONSTANTS["beta"])):
            paper = ln
        elif np.allclose(y, cel_dpbar_dp0(x, mu=consts[1], beta=consts[2])):
            fitted = ln
    assert paper is not None and fitted is not None

    def look(ln):
        return mcolors.to_hex(ln.get_color()), str(ln.get_linestyle()), ln.get_linewidth()

    assert all(a != b for a, b in zip(look(paper), look(fitted), strict=True)), (look(paper), look(fitted))
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert any(lab.startswith("paper:") and "0.21" in lab and "0.55" in lab for lab in labels), labels
    assert any(f"{consts[2]:.3f}" in lab and f"{consts[1]:.3f}" in lab for lab in labels), labels


def test_area_load_persson_lines_differ_and_bands_show(contact):
    from roughcontact.figures.load_curves import PERSSON_COLOUR
    from roughcontact.theory.laws import KAPPA_PERSSON, linear_area, persson_area

    agg, stats, fit = contact
    fig = fig_area_load(agg, stats, fit)
    ax = fig.axes[0]
    hp = float(stats["rms_slope_mean"].mean())
    lines = {}
    for ln in ax.get_lines():
        x, y = np.asarray(ln.get_xdata()), np.asarray(ln.get_ydata())
        if x.size != 200:
            continue
        if np.allclose(y, persson_area(x, rms_slope=hp, e_star=1.0)):
            lines["erf"] = ln
        elif np.allclose(y, linear_area(x, kappa=KAPPA_PERSSON, rms_slope=hp, e_star=1.0)):
            lines["limit"] = ln
    assert set(lines) == {"erf", "limit"}
    erf, limit = lines["erf"], lines["limit"]
    # One colour for Persson; the limit is dashed on top of a wide erf line, so both show where they meet.
    assert mcolors.to_hex(erf.get_color()) == mcolors.to_hex(limit.get_color()) == PERSSON_COLOUR.lower()
    assert erf.get_linewidth() >= 2 * limit.get_linewidth() and limit.get_zorder() > erf.get_zorder()
    assert str(erf.get_linestyle()) != str(limit.get_linestyle())
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert sum(lab.startswith("Persson, small-load limit") for lab in labels) == 1
    assert sum(lab.startswith("Persson, full") and "erf" in lab for lab in labels) == 1
    bands = [c for c in ax.collections if c.get_paths() and len(c.get_paths()[0].vertices) > 10]
    assert bands
    for band in bands:
        assert band.get_facecolor()[0][3] >= 0.25 and band.get_linewidth()[0] > 0
    assert any(lab.startswith(r"$\pm 1$ s.d. over seeds") for lab in labels), labels


def _map_axes(fig):
    return [ax for ax in fig.axes if ax.get_label() == "epsilon map"]


def test_representativity_map_is_drawn_only_for_a_two_dimensional_grid(rep_stats):
    """The paper's Fig. 1a: eps as colour over k_l x k_s, when both have >= 2 values with data."""
    fig = fig_representativity(rep_stats)
    (ax,) = _map_axes(fig)
    (mesh,) = [c for c in ax.collections if hasattr(c, "get_array")]
    free = rep_stats["epsilon_mean"].sel(H=0.8) * np.sqrt(0.1)  # fixture: sigma = 0.1 in every case
    np.testing.assert_allclose(np.asarray(mesh.get_array()).reshape(3, 3), free.values, rtol=1e-9)
    assert [t.get_text() for t in ax.get_xticklabels()] == ["32", "64", "128"]
    assert [t.get_text() for t in ax.get_yticklabels()] == ["1", "4", "16"]
    assert not _map_axes(fig_representativity(rep_stats.sel(k_s=[32.0])))
    assert not _map_axes(fig_representativity(rep_stats.sel(k_l=[4.0])))


def test_representativity_shows_the_scale_free_epsilon_beside_the_paper_one(rep_stats):
    import json

    rep = rep_stats.assign_attrs(scene_parameters=json.dumps({"surface": {"N": 256, "rms_height": 0.1}}),
                                 n_bins=500)
    fig = fig_representativity(rep)
    dim_ax, free_ax = fig.axes[0], fig.axes[1]
    assert "(h-\\bar h)/\\sigma" in free_ax.get_title() and free_ax.get_ylabel().endswith("[1]")
    assert "^-1/2" not in dim_ax.get_ylabel() and "$" in dim_ax.get_ylabel()
    for dim_line, free_line in zip(dim_ax.get_lines(), free_ax.get_lines(), strict=True):
        np.testing.assert_allclose(free_line.get_ydata(), np.asarray(dim_line.get_ydata()) * np.sqrt(0.1))
    title = fig._suptitle.get_text()
    for part in ("$N = 256$", "3 seeds", "500 bins", "$H = 0.8$", r"$\sigma$ = 0.1"):
        assert part in title, title
    # Without per-case heights' sigma only the paper's eps can be drawn.
    stats_only = rep.drop_vars(["epsilon", "std_height"])
    texts = [t for ax in fig_representativity(stats_only).axes for t in (ax.get_ylabel(), ax.get_title())]
    assert not any(r"\varepsilon_\sigma" in t for t in texts), texts


def test_the_longest_wavelength_reads_l_as_the_paper_writes_it():
    # k_l = 1 is lambda_l = L (the paper's notation), not "L/1"; other k read L/k
    dss, names = simulate_cel_cases(k_l=(1.0, 16.0), k_s=(32.0,), hurst=(0.84,), seeds=range(2),
                                    point_noise=1e-4, seed_scatter=0.01, rng_seed=5)
    agg = aggregate_contact(dss, names)
    fig = fig_kappa(agg, seed_statistics(agg))
    labels = [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    assert r"$\lambda_l = L$" in labels and r"$\lambda_l = L/16$" in labels
    assert not any("L/1$" in text for text in labels)


# ------------------------------------------------------ issue 24: unconverged steps
#: The unconverged steps of the test: family (k_l, k_s, H) -> (seeds, steps).
_UNCONVERGED = {(16.0, 32.0, 0.84): ([0, 1], list(range(20, 26))), (4.0, 128.0, 0.36): ([2], [30])}


def _with_unconverged(agg, unconverged=None):
    """``agg`` (and its seed statistics) with the steps of ``unconverged`` (default :data:`_UNCONVERGED`,
    family -> (seeds, steps)) unconverged, as a solve
    stopped by ``max_iter`` leaves them: ``pbar`` 20 times too small (kappa ~ 50), ``A/A0`` 3 times too
    large; kappa, d pbar/d p0 and n_unconverged derived again. Returns ``(agg, stats, mask)``."""
    from roughcontact.analysis.aggregate.derived import add_derived

    mask = xr.zeros_like(agg["converged"], dtype=bool)
    for (kl, ks, h), (seeds, steps) in (unconverged or _UNCONVERGED).items():
        mask.loc[{"k_l": kl, "k_s": ks, "H": h, "seed": seeds, "step": steps}] = True
    out = agg.drop_vars(["kappa", "dpbar_dp0", "n_unconverged"])
    out["converged"] = agg["converged"] & ~mask
    out["mean_contact_pressure"] = agg["mean_contact_pressure"].where(~mask, agg["mean_contact_pressure"] / 20)
    out["area_fraction"] = agg["area_fraction"].where(~mask, agg["area_fraction"] * 3)
    out = add_derived(out)
    return out, seed_statistics(out), mask


def _unconverged_labels(fig):
    return [t.get_text() for leg in fig.legends for t in leg.get_texts() if "unconverged" in t.get_text()]


def _crosses(ax):
    return [ln for ln in ax.get_lines() if ln.get_marker() == "x" and ln.get_linestyle() == "None"]


def _converged_mean(agg, var, family):
    case = agg.sel(dict(zip(("k_l", "k_s", "H"), family, strict=True)))
    return case[var].where(case["converged"]).mean("seed").transpose("step").values


def test_kappa_leaves_unconverged_steps_out_of_the_means_and_counts_them(contact):
    """Issue 24: with max_iter too small kappa reaches ~50 at the unconverged steps; those steps are not
    in the seed means (nor the axis range), are drawn as grey crosses and counted in the legend."""
    agg, stats, fit = contact
    bad_agg, bad_stats, mask = _with_unconverged(agg)
    assert float(bad_agg["kappa"].where(mask).max()) > 40
    fig = fig_kappa(bad_agg, bad_stats, fit)
    ax = fig.axes[0]  # k_s = 32
    means = [np.asarray(c.lines[0].get_ydata(), float) for c in ax.containers]
    expected = _converged_mean(bad_agg, "kappa", (16.0, 32.0, 0.84))
    assert any(np.allclose(y, expected, equal_nan=True) for y in means)
    assert all(np.nanmax(y) < 4 for y in means) and ax.get_ylim()[1] < 4, ax.get_ylim()
    (crosses,) = _crosses(ax)
    np.testing.assert_allclose(np.sort(crosses.get_ydata()), np.sort(bad_agg["kappa"].sel(k_s=32.0).values[
        mask.sel(k_s=32.0).values]))
    (label,) = _unconverged_labels(fig)
    assert label.startswith("13 unconverged load steps, left out of the lines and means"), label
    # the workflow's aggregate holds the seed statistics too, and is passed as both
    merged = bad_agg.merge(bad_stats)
    assert _unconverged_labels(fig_kappa(merged, merged, fit)) == [label]
    # all converged, or a file without `converged`: no such entry, no crosses
    for data in (agg, agg.drop_vars("converged")):
        fig = fig_kappa(data, stats, fit)
        assert not _unconverged_labels(fig) and not _crosses(fig.axes[0])


def test_area_load_and_dpbar_leave_unconverged_steps_out(contact):
    """The same for A/A0(p0) (mean and s.d. band) and d pbar/d p0 (faint finite differences, windows)."""
    agg, stats, fit = contact
    bad_agg, bad_stats, mask = _with_unconverged(agg)
    fig = fig_area_load(bad_agg, bad_stats, fit)
    ys = [np.asarray(ln.get_ydata(), float) for ln in fig.axes[0].get_lines() if ln.get_markevery() == 3]
    expected = _converged_mean(bad_agg, "area_fraction", (16.0, 32.0, 0.84))
    assert any(y.size == expected.size and np.allclose(y, expected, equal_nan=True) for y in ys)
    old = bad_stats["area_fraction_mean"].sel(k_l=16.0, k_s=32.0, H=0.84).values
    assert not any(y.size == old.size and np.allclose(y, old) for y in ys)
    assert len(_crosses(fig.axes[0])) == 1
    assert [lab.split(";")[0] for lab in _unconverged_labels(fig)] == [
        "13 unconverged load steps, left out of the lines and means"]
    fig = fig_dpbar(bad_agg, bad_stats, fit)
    faint = [np.asarray(ln.get_ydata(), float) for ln in fig.axes[0].get_lines() if (ln.get_alpha() or 1) < 0.5]
    raw = _converged_mean(bad_agg, "dpbar_dp0", (16.0, 32.0, 0.84))
    raw = raw[np.isfinite(raw) & (raw > 0)]
    assert any(y.size == raw.size and np.allclose(y, raw) for y in faint)
    assert [lab.split(";")[0] for lab in _unconverged_labels(fig)] == [
        "13 unconverged load steps, left out of the lines and means"]
    for draw in (fig_area_load, fig_dpbar):
        assert not _unconverged_labels(draw(agg, stats, fit))


def test_measured_figures_count_the_unconverged_steps_they_leave_out():
    from roughcontact.figures.measured import fig_measured_area_load, fig_measured_kappa

    dss, names = simulate_cel_cases(seeds=range(3), point_noise=1e-3, seed_scatter=0.0, area_max=0.13, rng_seed=3)
    cases, _, _ = _with_unconverged(aggregate_contact(dss, names), {(16.0, 32.0, 0.5): ([1, 2], list(range(20, 26)))})
    agg = cases.isel(k_l=0, k_s=0, H=0, drop=True).rename(seed="topography")
    agg = agg.assign_coords(topography=np.array(["a", "b", "c"], dtype=object))
    for draw in (fig_measured_area_load, fig_measured_kappa):
        fig = draw(agg)
        labels = _unconverged_labels(fig)
        assert [lab.split(";")[0] for lab in labels] == ["12 unconverged load steps, left out of the lines"], labels
        assert len(_crosses(fig.axes[0])) == 1
        lines = [ln for ln in fig.axes[0].get_lines() if ln.get_linestyle() == "-" and len(ln.get_xdata()) in (24, 30)]
        assert sorted(len(ln.get_xdata()) for ln in lines)[:2] == [24, 24]
        assert not _unconverged_labels(draw(agg.assign(converged=agg["converged"] | True)))


def test_captions_name_exactly_the_reference_lines_each_figure_draws(contact):
    """The area-load caption promises the asperity models at the surfaces' own alpha only where they are drawn:
    for one family, not for families of different bandwidth (issue 52)."""
    from caption_check import assert_caption_says_the_record, assert_caption_true, lead_of
    from roughcontact.figures.captions import caption
    from roughcontact.figures.record import figure_record

    def text(name, fig):
        record = figure_record(name, fig)
        out = caption(lead_of(name), record)
        assert_caption_says_the_record(record, out)
        return out

    agg, stats, fit = contact
    one = {"k_l": [16.0], "k_s": [32.0]}
    for name, draw in (("area_load", fig_area_load), ("kappa", fig_kappa), ("dpbar", fig_dpbar)):
        both = draw(agg.sel(one), stats.sel(one), fit.sel(one))
        shown = assert_caption_true(both, text(name, both))
        assert {"asperity_bgt_own", "cel_fit"} <= set(shown) if name != "dpbar" else "dpbar_fit" in shown
        mixed = draw(agg, stats, fit)
        shown = assert_caption_true(mixed, text(name, mixed))
        assert "asperity_bgt_own" not in shown and "surfaces' own" not in text(name, mixed)
        bare = draw(agg, stats)  # no fit: no fitted law named
        assert "fitted" not in text(name, bare).split("Drawn with the data")[-1]


def test_reference_lines_are_told_apart_and_lie_above_the_bands(contact):
    """BGT's small-load limit and the BGT asperity model at alpha = 2 were both solid black (issue 52)."""
    from matplotlib.collections import PolyCollection

    agg, stats, fit = contact
    one = {"k_l": [16.0], "k_s": [32.0]}
    ax = fig_area_load(agg.sel(one), stats.sel(one), fit.sel(one)).axes[0]
    lines = {line.get_gid(): line for line in ax.get_lines() if line.get_gid() not in (None, "family")}
    assert lines["bgt_limit"].get_linestyle() == "-" and lines["asperity_bgt_paper"].get_linestyle() != "-"
    band = max(c.get_zorder() for c in ax.collections if isinstance(c, PolyCollection))
    data = max(line.get_zorder() for line in ax.get_lines() if line.get_gid() == "family")
    assert lines["cel_fit"].get_zorder() > max(band, data)  # the fit is drawn over the data it fits


def test_accuracy_figure_counts_the_settings_it_cannot_draw():
    """The reference tolerance has zero error: a log axis cannot show it, so the legend says so (issue 52)."""
    from roughcontact.figures.accuracy import fig_accuracy

    axis = ["N", "N", "tol", "tol", "seeds", "seeds", "defaults"]
    err = [0.03, 0.01, 0.0, 0.002, 0.02, 0.03, 0.01]
    value = ["256", "512", "1e-10", "1e-8", "2", "4", "-"]
    summary = xr.Dataset({"axis": ("variant", axis), "value": ("variant", value),
                          "work_per_case": ("variant", [1.0, 4.0, 3.0, 2.0, 2.0, 4.0, 2.0]),
                          **{f"err_{m}": ("variant", err) for m in ("kappa", "area", "kappa_corrected",
                                                                   "area_corrected")}},
                         attrs={"kappa_at": 0.05})
    labels = [t.get_text() for t in fig_accuracy(summary).legends[0].get_texts()]
    assert "tolerance (1 of 2 not drawn: zero error, the reference, or none)" in labels and "grid N" in labels
    assert "seeds" in labels


def test_area_load_panels_have_a_log_log_inset_for_small_loads(contact):
    """Each area-load panel repeats its seed means on log-log axes, with the BGT small-load limit (issue 52)."""
    agg, stats, fit = contact
    fig = fig_area_load(agg, stats, fit)
    for ax in (a for a in fig.axes if a.get_visible()):
        (inset,) = ax.child_axes
        assert inset.get_xscale() == inset.get_yscale() == "log"
        families = [line for line in ax.get_lines() if line.get_gid() == "family"]
        assert len(families) >= 2 and len(inset.get_lines()) == len(families) + 2
        assert {line.get_gid() for line in inset.get_lines()} >= {"bgt_limit", "persson_limit"}


# ------------------------------------------------------------ issue 60: what is drawn is what is said
def _caption_of(name, fig):
    from caption_check import assert_caption_says_the_record, lead_of
    from roughcontact.figures.captions import caption
    from roughcontact.figures.record import figure_record

    record = figure_record(name, fig)
    text = caption(lead_of(name), record)
    assert_caption_says_the_record(record, text)
    return record, text


def test_a_figure_of_profiles_names_only_the_2d_laws_it_drew(contact):
    """The profiles' note named the BGT limit, the paper's CEL and its power law on every figure: area_load draws
    neither the paper's CEL nor the power law, kappa no power law, dpbar no BGT limit nor CEL (issue 60)."""
    agg, stats, fit = contact
    lines = agg.assign_attrs(surface_dimension=1)
    named = {}
    for name, draw in (("area_load", fig_area_load), ("kappa", fig_kappa), ("dpbar", fig_dpbar)):
        record, text = _caption_of(name, draw(lines, stats, fit))
        note = text.split("Drawn with the data")[0]
        assert record["profiles"] and "These cases are profiles" in text
        named[name] = {law for law in ("BGT", "evolution law", "power law") if law in note}
        assert ("asperity models are not drawn" in note) == (name != "dpbar"), name
        assert ("Persson's curves hold" in note) == any(g.startswith("persson") for g in record["references"])
    assert named == {"area_load": {"BGT"}, "kappa": {"BGT", "evolution law"}, "dpbar": {"power law"}}, named
    _, text = _caption_of("area_load", fig_area_load(agg, stats, fit))  # 2-D surfaces: no note of profiles
    assert "profile" not in text and "comparison only" not in text


def test_the_caption_names_the_route_of_the_fit_drawn(contact):
    """area_load draws the joint least-squares fit, kappa and dpbar the paper's route: each caption names the one
    drawn, with its window, and none without a fit (issue 60: "fitted to this run" said neither)."""
    from roughcontact.figures.captions import ROUTES

    agg, stats, fit = contact
    for name, draw, route in (("area_load", fig_area_load, "joint"), ("kappa", fig_kappa, "paper"),
                              ("dpbar", fig_dpbar, "paper")):
        record, text = _caption_of(name, draw(agg, stats, fit))
        assert {f["route"] for f in record["fits"]} == {route} and record["window"] == [0.01, 0.11]
        assert ROUTES[route] in text and all(p not in text for r, p in ROUTES.items() if r != route), name
        assert "from 0.01 to 0.11" in text
        other = "paper" if route == "joint" else "joint"
        record, text = _caption_of(name, draw(agg, stats, fit, estimator=other))
        assert ROUTES[other] in text and ROUTES[route] not in text
        record, text = _caption_of(name, draw(agg, stats))
        assert not record["fits"] and record["window"] is None and not any(p in text for p in ROUTES.values())


def test_legends_give_each_fitted_constant_at_its_interval(contact):
    """The dpbar legend printed mu = 0.537 beside the result's 0.54 [0.15, 0.66] (issue 60): every legend
    rounds a constant to its interval by the report's rule."""
    agg, stats, fit = contact
    sel = {"k_l": 16.0, "k_s": 32.0, "H_group": "pooled", "estimator": "paper"}
    demo = fit.copy(deep=True)
    for var, value in (("value", 0.537), ("ci_low", 0.15), ("ci_high", 0.66)):
        demo[var].loc[{**sel, "constant": "mu"}] = value
    first, _ = _fit_law_labels(agg, stats, demo)
    assert r"$\mu$ = 0.54" in first and "0.537" not in first, first
    one = {"k_s": [32.0]}
    labels = [t.get_text() for t in fig_kappa(agg.sel(one), stats.sel(one), demo.sel(one)).legends[0].get_texts()]
    (label,) = [lab for lab in labels if lab.startswith("CEL fitted")]
    assert r"$\mu$ = 0.54" in label and rf"$\beta$ = {_at_interval(fit, 'beta')}" in label, label


@pytest.mark.parametrize(("value", "low", "high", "shown"), [
    (0.537, 0.15, 0.66, "0.54"), (1.0612, 1.0281, 1.1642, "1.06"), (1.466, 1.167, 3120.0, "1"),
    (0.0413, -0.5, 0.5, "0.04"), (0.0, -0.3, 0.4, "0.0"), (12345678.9, 12345670.0, 12345690.0, "12346000")])
def test_a_legend_value_keeps_the_figures_of_its_interval_and_is_never_a_false_zero(value, low, high, shown):
    """One figure of a half-width leading with 3 to 9 (0.068 -> 1.06, not 1.061); a value that is not 0 keeps one
    significant figure where its interval would round it to 0 (issue 60's "0 [0, 3100]")."""
    from roughcontact.figures.style import at_interval

    assert at_interval(value, low, high) == shown


def test_every_axis_of_the_lines_representativity_figure_has_readable_ticks():
    """The lines scene's representativity: eps 0.53-0.87 (panel a) had no y tick label, the scale-free eps
    0.17-0.28 (panel b) and the colour bar only "0.2" (issue 60): a log axis over less than a decade has no
    decade to label. Every axis, the colour bar's too, shows at least two labelled ticks."""
    from figure_builders import labelled_ticks, rep_stats

    rep = rep_stats(eps=lambda kl, ks: {(4.0, 64.0): 0.87, (4.0, 128.0): 0.79, (16.0, 64.0): 0.59,
                                        (16.0, 128.0): 0.53}[(kl, ks)], k_l=(4.0, 16.0), k_s=(64.0, 128.0),
                    std=0.1, seed=3)
    fig = fig_representativity(rep)
    fig.draw_without_rendering()
    axes = [ax for ax in fig.axes if ax.get_visible()]
    assert len(axes) == 4  # (a), (b), the map (c) and its colour bar
    for ax in axes:
        for axis in (ax.xaxis, ax.yaxis):
            if axis.get_scale() == "log" or ax.get_label() == "<colorbar>" and axis is ax.yaxis:
                labels = labelled_ticks(axis)
                assert len(labels) >= 2, (ax.get_title(), axis.axis_name, axis.get_view_interval(), labels)
