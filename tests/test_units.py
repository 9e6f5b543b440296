"""Every variable and coordinate the package writes carries a ``units`` string CF tools parse.

Every ``units`` must parse with UDUNITS-2 (``cf_units``, the CF conventions' reference) and pint
to the same unit. UDUNITS-2 has integer powers only, so ``cf_unit`` refuses fractional ones and
``epsilon`` [length^-1/2] is written as its number for lengths in the study's unit, ``units``
``"1"`` with its reference length alongside (roughcontact.core.quantities.per_reference_length).
"""
import ast
import math
from fractions import Fraction
from pathlib import Path

import pint
import pytest
from cf_units import Unit

from roughcontact.analysis import aggregate
from roughcontact.analysis.aggregate.seeds import scale_free_statistics
from roughcontact.analysis.fit.grid import fit_cel
from roughcontact.core.quantities import LENGTH_UNITS, PRESSURE_UNITS, cf_unit, per_reference_length
from roughcontact.figures.style import unit_tex
from roughcontact.pipeline.datasets import (
    contact_dataset,
    representativity_batch,
    representativity_dataset,
    split_cases,
    surface_dataset,
)
from roughcontact.solver import solve_contact
from roughcontact.statistics.clusters import ClusterObserver
from roughcontact.statistics.representativity import gaussian_l2_error
from roughcontact.studies import accuracy
from roughcontact.surfaces.synthetic import generate_surface, spectral_moments

SRC = Path(__file__).resolve().parents[1] / "src" / "roughcontact"
UREG = pint.UnitRegistry()

#: (length_power, pressure_power) of the quantities the package writes (and a pressure gradient).
POWERS = [(0, 0), (1, 0), (2, 0), (-1, 0), (-2, 0), (0, 1), (-1, 1)]
#: Size of each declared unit in SI.
SI = {"1": 1.0, "m": 1.0, "mm": 1e-3, "um": 1e-6, "nm": 1e-9,
      "Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9}


def assert_parses(units: str) -> None:
    """``units`` parses with UDUNITS-2 (cf_units) to a unit, and with pint."""
    assert isinstance(units, str) and units.strip(), repr(units)
    unit = Unit(units)
    assert not unit.is_unknown() and not unit.is_no_unit(), units
    assert UREG.parse_expression(units).dimensionless == unit.is_dimensionless(), units


def assert_reference(attrs: dict) -> None:
    """A value written as a number for lengths in a reference unit: units "1", the unit UDUNITS-2's."""
    assert attrs["units"] == "1" and Fraction(attrs["reference_length_power"]).denominator > 1, attrs
    assert_parses(attrs["reference_length_units"])


def assert_all_units_parse(ds) -> dict:
    """Every data variable and coordinate of ``ds`` has a parsable ``units``; returns name -> units."""
    units = {}
    for name, var in ds.variables.items():
        assert "units" in var.attrs, f"{name} has no units attribute"
        assert_parses(var.attrs["units"])
        if "reference_length_units" in var.attrs:
            assert_reference(var.attrs)
        units[name] = var.attrs["units"]
    return units


# ------------------------------------------------------------------------------- composer
@pytest.mark.parametrize("length", LENGTH_UNITS)
@pytest.mark.parametrize("pressure", PRESSURE_UNITS)
def test_composed_units_parse_to_the_right_size_with_udunits_and_pint(length, pressure):
    for lp, pp in POWERS:
        units = cf_unit(length, pressure, length_power=lp, pressure_power=pp)
        si = cf_unit("m" if length != "1" else "1", "Pa" if pressure != "1" else "1",
                     length_power=lp, pressure_power=pp)
        factor = SI[length] ** float(lp) * SI[pressure] ** float(pp)
        assert UREG.Quantity(1.0, UREG.parse_units(units)).to(UREG.parse_units(si)).magnitude == \
            pytest.approx(factor, rel=1e-12), units
        assert Unit(units).convert(1.0, Unit(si)) == pytest.approx(factor, rel=1e-12), units
        assert units.isascii() and "(" not in units and "." not in units, units
        if length == "1" and pressure == "1":
            assert units == "1"


def test_composer_spellings():
    assert cf_unit("um", length_power=1) == "um"
    assert cf_unit("um", length_power=2) == "um^2"
    assert cf_unit("um", length_power=-2) == "um^-2"
    assert cf_unit("nm", length_power=2.0) == cf_unit("nm", length_power=Fraction(2)) == "nm^2"
    assert cf_unit("um", "MPa", pressure_power=1) == "MPa"
    assert cf_unit("um", "MPa", length_power=-1, pressure_power=1) == "MPa um^-1"
    assert cf_unit("1", "MPa", length_power=-1, pressure_power=1) == "MPa"
    assert cf_unit("um", "MPa") == "1"
    for bad in ({"length": "cm"}, {"pressure": "bar"}, {"length": "um", "length_power": math.pi},
                {"length": "um", "pressure_power": True}):
        with pytest.raises(ValueError):
            cf_unit(**bad)


@pytest.mark.parametrize("power", [Fraction(-1, 2), -0.5, Fraction(3, 2)])
def test_fractional_powers_are_refused_and_written_as_numbers(power):
    with pytest.raises(ValueError, match="integer powers only.*per_reference_length"):
        cf_unit("um", length_power=power)
    attrs = per_reference_length("um", power)
    assert attrs == {"units": "1", "reference_length_units": "um", "reference_length_power": str(Fraction(power))}
    assert_reference(attrs)
    assert per_reference_length("1", power)["reference_length_units"] == "1"
    with pytest.raises(ValueError):
        per_reference_length("um", math.pi)


def test_udunits_has_no_fractional_powers():
    """Why epsilon is written as a number: UDUNITS-2 reads ``um^-0.5`` as ``um^-0 . 5``, the number 5, and
    rejects every other spelling of um^-1/2 (pint reads them all)."""
    assert Unit("um^-0.5").is_dimensionless() and Unit("um^-0.5").convert(1.0, "1") == pytest.approx(5.0)
    for spelling in ("um^(-1/2)", "um^(-0.5)", "um**(-1/2)"):
        with pytest.raises(ValueError):
            Unit(spelling)
        assert UREG.parse_units(spelling).dimensionality == UREG.parse_units("um^-0.5").dimensionality
    with pytest.raises(ValueError):
        Unit("um").root(2)


def test_axis_labels_render_the_unit_strings():
    from matplotlib.mathtext import MathTextParser

    parser = MathTextParser("agg")
    assert unit_tex("1") == "1"
    assert unit_tex("um^(-1/2)") == r"$\mathrm{\mu m}^{-1/2}$"
    assert unit_tex("MPa um^-1") == r"$\mathrm{MPa}\,\mathrm{\mu m}^{-1}$"
    for length in LENGTH_UNITS:
        for pressure in PRESSURE_UNITS:
            for lp, pp in POWERS:
                tex = unit_tex(cf_unit(length, pressure, length_power=lp, pressure_power=pp))
                assert "^(" not in tex and "um" not in tex, tex
                if tex != "1":
                    parser.parse(tex)


# ------------------------------------------------------------------------------- datasets
LOADS = [0.001, 0.003, 0.006]  # A/A0 from about 0.02 to 0.12 at rms slope 0.1, E* = 1
SURFACE = {"N": 32, "L": 1.0, "plateau": False, "rms_slope": 0.1}


@pytest.fixture(scope="module", params=[("1", "1"), ("um", "MPa")], ids=["nondimensional", "um-MPa"])
def written(request):
    """Every kind of dataset the package writes, built with the given (length, pressure) units."""
    lu, pu = request.param
    kw = {"k_l": "2", "k_s": "8", "hurst": "0.8"}
    out = {}
    contacts = []
    for seed in (0, 1):
        h = generate_surface(32, 2.0, 8.0, 0.8, seed, rms_slope=0.1, length=1.0)
        surf = surface_dataset(h, seed=seed, length=1.0, normalisation={"rms_slope": 0.1}, length_unit=lu, **kw)
        rep = representativity_dataset(gaussian_l2_error(h, 20), h, n_bins=20, seed=seed, length_unit=lu, **kw)
        result = solve_contact(h, LOADS, store_fields=[1], hardness=1.0, length_unit=lu, pressure_unit=pu,
                               observers=[ClusterObserver(1.0, length_unit=lu)])
        stats = spectral_moments(h, 1.0)
        contacts.append(contact_dataset(result, rms_slope=stats["rms_slope"], alpha=stats["alpha"], e_star=1.0,
                                        seed=seed, **kw))
        if seed == 0:
            out.update(surface=surf, representativity=rep, solver=result, contact=contacts[0])
    names = ["s0.nc", "s1.nc"]
    agg = aggregate.aggregate_contact(contacts, names)
    out["aggregate_contact"] = agg.merge(aggregate.seed_statistics(agg))
    batch = representativity_batch({**SURFACE, "unit": lu}, seeds=2, n_bins=20, k_l=kw["k_l"], k_s=[kw["k_s"]],
                                   hurst=kw["hurst"])
    out["representativity_batch"] = batch
    rep_agg = aggregate.combine_cases(split_cases(batch), names, kind="representativity")
    out["aggregate_representativity"] = rep_agg.merge(aggregate.representativity_statistics(rep_agg))
    out["scale_free"] = scale_free_statistics(rep_agg)
    out["fit"] = fit_cel(agg, n_boot=10, on_insufficient="nan", window=(0.01, 0.2), min_points=3)
    setting = {"label": "N32", "value": "", "N": "32", "tol": "1e-8", "n_steps": "3", "seeds": 2}
    out["accuracy"] = accuracy.summarize({"N32": agg},
                                         [{**setting, "axis": "reference"}, {**setting, "axis": "defaults"}],
                                         length=1.0, kappa_at=0.05, n_boot=10, length_unit=lu)
    return lu, pu, out


def test_every_written_variable_has_parsable_units(written):
    _, _, out = written
    for kind, ds in out.items():
        try:
            assert_all_units_parse(ds)
        except AssertionError as err:
            raise AssertionError(f"{kind}: {err}") from None


def test_units_follow_the_declared_length_and_pressure_units(written):
    lu, pu, out = written
    length, pressure = cf_unit(lu, length_power=1), cf_unit(pressure=pu, pressure_power=1)
    expect = {
        "surface": {"heights": length, "rms_height": length, "x": length, "y": length, "rms_slope": "1",
                    "m0": cf_unit(lu, length_power=2), "m2": "1", "m4": cf_unit(lu, length_power=-2), "alpha": "1",
                    "k_l": "1", "seed": "1"},
        "representativity": {"epsilon": "1", "mean_height": length, "std_height": length},
        "solver": {"pressure": pressure, "mean_contact_pressure": pressure, "contact_pressure": pressure,
                   "mean_gap": length, "gap": length, "x": length, "contact_perimeter": cf_unit(lu, length_power=-1),
                   "area_fraction": "1", "cluster_mean_area": "1", "area_bin": "1", "wall_time": "s",
                   "plastic_load_fraction": "1", "step": "1", "field_step": "1"},
        "contact": {"pressure": pressure, "kappa": "1", "area_fraction_corrected": "1", "gap": length},
        "aggregate_contact": {"pressure": pressure, "mean_contact_pressure_mean": pressure,
                              "mean_contact_pressure_sem": pressure, "pressure_mean": pressure,
                              "kappa_mean": "1", "dpbar_dp0_std": "1", "mean_gap": length,
                              "contact_perimeter": cf_unit(lu, length_power=-1), "n_seeds": "1"},
        "representativity_batch": {"epsilon": "1", "std_height": length},
        "aggregate_representativity": {"epsilon_mean": "1", "epsilon_sem": "1", "std_height": length},
        "scale_free": {"epsilon_mean": "1"},
        "accuracy": {"work_per_case": "1", "err_kappa": "1"},
    }
    for kind, wanted in expect.items():
        got = {name: out[kind][name].attrs["units"] for name in wanted}
        assert got == wanted, kind
    for kind in ("solver", "contact", "aggregate_contact"):
        assert out[kind].attrs["pressure_units"] == pressure and out[kind].attrs["length_units"] == length
    for kind in ("surface", "accuracy"):
        assert out[kind].attrs["length_units"] == length
    for kind, name in [("representativity", "epsilon"), ("representativity_batch", "epsilon"),
                       ("aggregate_representativity", "epsilon"), ("aggregate_representativity", "epsilon_mean"),
                       ("aggregate_representativity", "epsilon_std")]:
        attrs = out[kind][name].attrs
        assert (attrs["reference_length_units"], attrs["reference_length_power"]) == (length, "-1/2"), (kind, name)
    assert "reference_length_units" not in out["scale_free"]["epsilon_mean"].attrs  # normalised by sigma instead
    if lu == "um":
        assert out["representativity"]["epsilon"].attrs["reference_length_units"] == "um"
        assert out["solver"]["contact_perimeter"].attrs["units"] == "um^-1"
        assert out["surface"]["m4"].attrs["units"] == "um^-2" and out["solver"]["pressure"].attrs["units"] == "MPa"


def test_aggregation_refuses_cases_in_different_units(written):
    lu, pu, out = written
    other = out["contact"].copy()
    other["pressure"] = other["pressure"].assign_attrs(units="GPa" if pu != "GPa" else "Pa")
    with pytest.raises(ValueError, match="units"):
        aggregate.combine_cases([out["contact"], other.assign_coords(seed=[7])], ["a.nc", "b.nc"])
    # epsilon's units are "1" in every length unit: its reference length tells the cases apart
    rep = out["representativity"]
    other = rep.assign(epsilon=rep["epsilon"].assign_attrs(reference_length_units="nm" if lu != "nm" else "m"))
    with pytest.raises(ValueError, match="variable 'epsilon' has units '1 \\(lengths in n?m\\)'"):
        aggregate.combine_cases([rep, other.assign_coords(seed=[7])], ["a.nc", "b.nc"], kind="representativity")


def test_kappa_needs_one_pressure_unit(written):
    _, pu, out = written
    agg = out["aggregate_contact"]
    bad = agg.assign(mean_contact_pressure=agg["mean_contact_pressure"].assign_attrs(units="Pa m^-1"))
    with pytest.raises(ValueError, match="one unit"):
        aggregate.add_derived(bad)
    with pytest.raises(ValueError, match="one unit"):
        aggregate.add_derived(agg.assign_attrs(pressure_units="GPa" if pu != "GPa" else "Pa"))


def test_solver_refuses_undeclared_units():
    h = generate_surface(16, 2.0, 4.0, 0.8, 0, rms_slope=0.1)
    with pytest.raises(ValueError, match="length unit"):
        solve_contact(h, [0.001], length_unit="cm")
    with pytest.raises(ValueError, match="pressure unit"):
        solve_contact(h, [0.001], pressure_unit="bar")


# --------------------------------------------------------------------------- source scan
OLD_SPELLINGS = ("same as", "length unit", "unit of", "height unit")


def _unit_values(tree):
    """String constants that are (part of) a ``units`` attribute in the source."""
    for node in ast.walk(tree):
        values = []
        if isinstance(node, ast.Dict):
            values = [v for k, v in zip(node.keys, node.values, strict=True)
                      if isinstance(k, ast.Constant) and k.value == "units"]
        elif isinstance(node, ast.Call):
            values = [kw.value for kw in node.keywords if kw.arg == "units"]
        elif isinstance(node, ast.Assign):
            if any(isinstance(t, ast.Name) and t.id.upper().endswith("UNITS") for t in node.targets):
                values = [node.value]
        for value in values:
            for sub in ast.walk(value):
                if isinstance(sub, ast.Constant) and isinstance(sub.value, str):
                    yield sub


def test_no_placeholder_units_in_the_source():
    files = sorted(SRC.rglob("*.py"))
    assert len(files) > 10
    found = 0
    for path in files:
        text = path.read_text()
        for const in _unit_values(ast.parse(text)):
            found += 1
            assert not any(s in const.value.lower() for s in OLD_SPELLINGS), \
                f"{path.name}:{const.lineno}: units {const.value!r}"
        for old in ("same as e_star", "same as heights", "length unit of L"):
            assert old not in text, f"{path.name}: {old!r}"
    assert found > 20  # the scan sees the units attributes
