"""What each kind of job depends on: the exact, canonical parameters of one job.

Snakemake reruns a job when its ``params`` change, and every output file records the
parameters that produced it. Both must therefore hold exactly the values the job's output
depends on — nothing from elsewhere in the scene (adding a seed must not touch existing
cases; a solver tolerance must not touch surfaces; a description touches nothing) — in one
canonical form: keys sorted at every level, numbers typed by the schema (done by
:func:`roughcontact.pipeline.scenes.validate_config`). One provider per kind of job, as PyPSA-Eur's
``config_provider`` hands single keys to rules. Every function takes a *validated* block
and returns a new plain ``dict`` of JSON types.
"""

from __future__ import annotations

import json
from collections.abc import Mapping

from .case import follows_elastic_law


def canonical(obj):
    """``obj`` with every mapping's keys sorted (recursively); lists keep their order."""
    if isinstance(obj, Mapping):
        return {key: canonical(obj[key]) for key in sorted(obj)}
    if isinstance(obj, (list, tuple)):
        return [canonical(item) for item in obj]
    return obj


def _pick(block: Mapping, keys) -> dict:
    return canonical({key: block[key] for key in keys if key in block})


def surface(block: Mapping) -> dict:
    """A surface job (either study): the surface block (N, L, plateau, normalisation, unit; ``dimension: 1`` for
    profiles: ``dimension: 2``, the maps every scene made before it existed, is left out, so writing it changes
    no job's parameters)."""
    out = _pick(block["surface"], ("N", "L", "plateau", "rms_slope", "rms_height", "unit", "dimension"))
    if out.get("dimension") == 2:
        del out["dimension"]
    return out


def representativity(block: Mapping) -> dict:
    """A representativity job: bins, and for generated surfaces the seeds, the k_s list and the surface block.

    A generated job computes one ``(k_l, H)`` batch over every k_s of the grid (its file
    holds them all, so adding a k_s reruns the batches). A measured scene's block has
    none of these (its surface is the file the job reads).
    """
    out = _pick(block, ("n_bins", "seeds"))
    if "surface" in block:
        out["surface"] = surface(block)
    if "grid" in block:
        out["k_s"] = list(block["grid"]["k_s"])
    return canonical(out)


def contact(block: Mapping) -> dict:
    """A contact job: load schedule, solver settings, optional outputs and effects."""
    return _pick(block, ("load", "solver", "outputs", "effects"))


def fit(scene: Mapping) -> dict:
    """The CEL fit of a scene: its ``fit`` block."""
    return canonical(scene["fit"])


def accuracy_case(block: Mapping, setting: Mapping) -> dict:
    """One accuracy case: surface normalisation, final load and the setting's N, tol, steps."""
    return canonical({
        "surface": block["surface"],
        "p_max": block["p_max"],
        "setting": {key: setting[key] for key in ("N", "tol", "n_steps")},
    })


def accuracy_summary(block: Mapping) -> dict:
    """The accuracy summary: the whole accuracy block (every setting and the error measures)."""
    return canonical(block)


def kappa_gap_case(block: Mapping, label: str) -> dict:
    """One kappa-gap solve: the surface normalisation, gap thresholds and the variant's setting."""
    return canonical({
        "surface": block["surface"],
        "gap_thresholds": block["gap_thresholds"],
        "variant": label,
        # What the job computes, not how many seeds its variant has nor the role it plays in the table.
        "setting": {k: v for k, v in block["variants"][label].items() if k not in ("seeds", "role")},
    })


def kappa_gap_summary(block: Mapping) -> dict:
    """The kappa-gap table: the whole block (every variant)."""
    return canonical(block)


def summary(scene: Mapping) -> dict:
    """The report's summary of a scene: its study blocks and, with a contact study whose effects keep the contact
    evolution law (none adhesive), its fit.

    Not its description (free text), nor ``keep_surfaces`` (whether surface files are kept,
    which changes no result).
    """
    blocks = {key: scene[key] for key in ("representativity", "contact", "accuracy", "kappa_gap") if key in scene}
    if "contact" in scene and follows_elastic_law(scene["contact"]):  # else no fit
        blocks["fit"] = scene["fit"]
    return canonical({
        key: {k: v for k, v in block.items() if k != "keep_surfaces"} for key, block in blocks.items()
    })


def recorded(ds) -> dict:
    """The parameters a file of this package records (its ``scene_parameters`` attribute).

    Raises ``ValueError`` naming the file's source if the attribute is missing or not JSON.
    """
    text = ds.attrs.get("scene_parameters")
    if text is None:
        raise ValueError(f"{ds.encoding.get('source', 'dataset')}: no 'scene_parameters' attribute")
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise ValueError(f"{ds.encoding.get('source', 'dataset')}: 'scene_parameters' is not JSON: {exc}") from None


def _same_label(got, want) -> bool:
    """Whether a case coordinate's value is the one asked for: numbers by value, names as text."""
    if isinstance(got, (str, bytes)) or isinstance(want, str) and not _is_number(want):
        return str(got) == str(want)
    return float(got) == float(want)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def require_made_for(ds, path, case: Mapping, **expected) -> None:
    """Raise ``ValueError`` naming ``path`` unless it holds ``case`` made with ``expected``.

    ``case`` maps ``k_l, k_s, H, seed`` to the values the job asks for (config strings or
    numbers), or ``topography`` to a measured case's name; ``expected`` maps keys of the
    file's recorded parameters (e.g. ``surface``) to
    the values the job needs. Guards against a file of another case or scene put in place.
    """
    for dim, want in case.items():
        got = ds[dim].values.ravel() if dim in ds.coords else None
        if got is None or got.size != 1 or not _same_label(got[0], want):
            raise ValueError(f"{path}: holds {dim}={None if got is None else got.tolist()}, but this job is "
                             f"for {dim}={want}; the file was made for another case")
    rec = recorded(ds)
    for key, want in expected.items():
        if canonical(rec.get(key)) != canonical(want):
            raise ValueError(f"{path}: was made with {key} = {canonical(rec.get(key))}, but this job needs "
                             f"{key} = {canonical(want)}; remove the file (or rerun with -f) to remake it")
