"""The report's introduction: the stages a scene runs, named from its validated config, and the contact evolution
law's formula only where the scene fits the law.

The landing page (``workflow/report/workflow.rst``) opens with this fragment, ``results/{scene}/report/intro.rst``,
which the ``report_summary`` rule writes: :func:`intro_facts` reduces a validated scene to what the introduction
says of it (JSON-able, the rule's params: a change of the scene's description or grid plans nothing), and
:func:`intro_rst` writes it. A scene's stages (:func:`scene_stages`) are those its blocks ask for: its surfaces
(generated, 1-D profiles, or a patch source's files), their representativity, contact (elastic, or as an effect
names it: adhesive contact), the fit of the contact evolution law (a contact study whose effects keep the law), the
accuracy study, the kappa-gap study. What an effect makes of contact (its stage's title and words) is the effect's
own (:class:`roughcontact.solver.effects.Effect` ``contact_name``, ``intro_fact``, ``intro_text``).
"""

from __future__ import annotations

from collections.abc import Mapping

from ..pipeline.case import contact_effects, follows_elastic_law
from ..pipeline.sources import source_of
from ..solver.effects import EFFECTS

#: The paper the package reproduces, as the introduction cites it.
PAPER = ('Yastrebov, Anciaux & Molinari, "Contact between representative rough surfaces", '
         "Phys. Rev. E 86, 035601 (2012)")

#: The effects that name contact their own way (:attr:`~roughcontact.solver.effects.Effect.contact_name`), by
#: their registered names: each is a stage of its own, in place of "contact".
CONTACT_EFFECTS = {name: effect for name, effect in EFFECTS.items() if effect.contact_name}

#: Each stage's name as the introduction writes it (bold, at the head of its item), in the order given.
STAGE_TITLES = {
    "surfaces": "surfaces",
    "representativity": "representativity",
    "contact": "contact",
    **{name: effect.contact_name for name, effect in CONTACT_EFFECTS.items()},
    "fit": "contact evolution law",
    "accuracy": "accuracy",
    "kappa_gap": "κ gap",
}

#: The contact evolution law (Yastrebov et al. 2012, Eq. 2) as a display formula.
CEL_MATH = (r".. math:: \frac{A}{A_0} = \left(\beta + \left[\frac{\kappa\, p_0}{h' E^*}\right]^{\mu-1}"
            r"\right)^{1/(\mu-1)}")

#: What a contact study stores beyond the load curves (``contact.outputs``), as the introduction names it.
OUTPUTS = {
    "fields": "the contact pressure and gap fields at load step{s} {steps} (the contact map)",
    "clusters": "the contact clusters at every step",
    "stiffness": "the normal contact stiffness",
    "pressure_distribution": "the distribution of the contact pressure",
    "full_contact_load": "each surface's full-contact load",
}


def _dimension(scene: Mapping) -> int:
    """The generated surfaces' dimension (1: profiles), from the contact block or else the representativity one."""
    for study in ("contact", "representativity"):
        if study in scene:
            return int(scene[study].get("surface", {}).get("dimension", 2))
    return 2


def intro_facts(scene: Mapping) -> dict:
    """What the introduction says of a validated scene (:func:`roughcontact.pipeline.scenes.validate_config`):
    its surface source, the number of files of a patch source, the generated surfaces' dimension, whether it
    computes representativity, its contact study (what an effect that names contact keeps of its parameters, by
    the effect's name: the adhesion law; and the stored outputs), the fit's window of
    ``A/A0`` (None without a fit), and whether it runs the accuracy and kappa-gap studies. JSON-able."""
    source = source_of(scene) if ("contact" in scene or "representativity" in scene) else None
    contact = None
    if "contact" in scene:
        block = scene["contact"]
        outputs, effects = block.get("outputs", {}), contact_effects(block)
        contact = {
            **dict.fromkeys(CONTACT_EFFECTS),
            **{effect.name: effect.intro_fact for effect in effects if effect.name in CONTACT_EFFECTS},
            "outputs": [k for k in OUTPUTS if outputs.get(k)],
            "fields": [int(s) for s in outputs.get("fields", [])],
        }
    fits = "contact" in scene and follows_elastic_law(scene["contact"])
    return {
        "source": None if source is None else source.name,
        "files": 0 if source is None else len(source.names(scene)),
        "dimension": _dimension(scene),
        "representativity": "representativity" in scene,
        "contact": contact,
        "fit": [float(v) for v in scene["fit"]["window"]] if fits else None,
        "accuracy": "accuracy" in scene,
        "kappa_gap": "kappa_gap" in scene,
    }


def scene_stages(facts: Mapping) -> list[str]:
    """The stages (keys of :data:`STAGE_TITLES`) a scene of ``facts`` (:func:`intro_facts`) runs, in order."""
    contact = facts.get("contact")
    stages = ["surfaces"] if facts.get("source") else []
    stages += ["representativity"] if facts.get("representativity") else []
    if contact is not None:
        stages.append(_contact_stage(contact))
    stages += ["fit"] if facts.get("fit") else []
    stages += ["accuracy"] if facts.get("accuracy") else []
    stages += ["kappa_gap"] if facts.get("kappa_gap") else []
    return stages


def _contact_stage(contact: Mapping) -> str:
    """The contact study's stage: an effect's that names contact (:data:`CONTACT_EFFECTS`), else ``contact``."""
    return next((name for name in CONTACT_EFFECTS if contact.get(name)), "contact")


def _surfaces(facts: Mapping) -> str:
    n, source = int(facts.get("files", 0)), facts.get("source")
    if source == "generated":
        what = ("self-affine random profiles (1-D surfaces, in plane strain)" if facts.get("dimension") == 1
                else "self-affine random surfaces")
        return (f"{what} by FFT filtering of white noise between the cutoffs :math:`\\lambda_l = L/k_l` and "
                ":math:`\\lambda_s = L/k_s`, Hurst exponent :math:`H`")
    files = f"{n} file{'s' if n != 1 else ''}"
    if source == "array":
        return f"{files} of heights given as arrays with their pixel size, as non-periodic patches"
    if source == "measured":
        return f"{files} of measured topography, as non-periodic patches"
    return f"{files} read by the {source} source, as non-periodic patches"


def _contact(contact: Mapping) -> str:
    stored = []
    for key in contact.get("outputs", []):
        steps = contact.get("fields", [])
        stored.append(OUTPUTS[key].format(s="s" if len(steps) != 1 else "", steps=", ".join(map(str, steps))))
    also = ("; it also stores " + ", ".join(stored[:-1]) + (" and " if len(stored) > 1 else "") + stored[-1]
            if stored else "")
    stage = _contact_stage(contact)
    if stage != "contact":
        return CONTACT_EFFECTS[stage].intro_text(contact[stage]) + also
    return f"frictionless elastic contact with a rigid flat, the load applied in steps{also}"


def _stage_text(stage: str, facts: Mapping) -> str:
    """The text of one stage's item after its title."""
    if stage == "surfaces":
        return _surfaces(facts)
    if stage == "representativity":
        return ("how Gaussian the heights are: the :math:`L_2` error between their distribution and a Gaussian,"
                + (" per pair of cutoffs, over seeds" if facts.get("source") == "generated" else " per file"))
    if stage == "contact" or stage in CONTACT_EFFECTS:
        return _contact(facts["contact"])
    if stage == "fit":
        low, high = facts["fit"]
        return (f"fitted to the load curves over :math:`A/A_0` from {low:g} to {high:g}, by the paper's route "
                "and by a joint least-squares fit")
    if stage == "accuracy":
        return ("the error of :math:`A/A_0`, :math:`\\kappa` and the fitted contact evolution law's constants against "
                "the solver's work, one setting (grid, tolerance, load steps, seeds) varied at a time around the "
                "most accurate one")
    if stage == "kappa_gap":
        return (r"how far each candidate cause (the solver and its stopping rule, what counts as contact, the "
                r"grid, the slope and load conventions) moves :math:`\kappa(A/A_0)` at the paper's "
                r"representative point")
    raise ValueError(f"unknown stage {stage!r}; known: {sorted(STAGE_TITLES)}")


def intro_rst(scene_name: str, facts: Mapping) -> str:
    """The landing page's introduction of scene ``scene_name`` (reStructuredText): the paper, then one item per
    stage the scene runs (:func:`scene_stages`), and the contact evolution law's formula where the scene fits
    the law (its contact study, or the accuracy study's fits)."""
    stages = scene_stages(facts)
    lines = [f"roughcontact computes the contact mechanics of representative rough surfaces after {PAPER}. "
             f"Scene **{scene_name}** runs {'this stage' if len(stages) == 1 else 'these stages'}:", ""]
    lines += [f"- **{STAGE_TITLES[s]}**: {_stage_text(s, facts)}." for s in stages]
    if "fit" in stages or "accuracy" in stages:
        lines += ["", "The contact evolution law:", "", CEL_MATH]
    return "\n".join(lines) + "\n"
