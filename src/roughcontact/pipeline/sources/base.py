"""What a surface source supplies to the pipeline, and the registry that finds a scene's source.

A *surface source* is where a scene's surfaces come from: the generator (``generated``), topography
files (``measured``), plain NumPy arrays (``array``), ... Each is one module in this package holding
one :class:`Source` subclass, registered with :func:`register` under its name. The config's
validation, the workflow's rules (:mod:`roughcontact.pipeline.targets`), its scripts, the figure registry
and the progress report ask the scene's source (:func:`source_of`) instead of testing which kind
of scene it is. A source says

* ``name``: its name in the registry; ``key``: the scene's config block that selects it (``None``
  for the source of a scene that names none: the generator); ``applies(scene)``: whether a scene
  uses it, from the scene's keys;
* ``case_keys`` and ``stem``: the wildcards of one case and its file stem pattern under
  ``results/{scene}/<stage>/`` (``kl{k_l}_ks{k_s}_H{H}_s{seed}``, or ``{topography}``);
* ``cases(scene, study)``: the case dicts of a study (wildcard -> value); ``stems``,
  ``batch_stems`` (the representativity files) and ``case_list`` (the aggregates' ``cases``
  parameter) follow from them; ``names(scene)``: the named cases (patch sources; [] otherwise);
* ``surface_rules``: the rules that make its surface datasets (a patch source's are made by the
  ``topography`` rule, which calls its ``read(settings)`` builder with ``reader_settings(scene,
  name)`` on ``input_file(scene, name)``);
* ``record_key``: the key under which a surface file records the settings it was made with;
* ``case_dims``: the aggregate's case dimension(s); :func:`for_dims` finds the source of a dataset;
* ``fit``: ``"grid"`` (``fit_cel``, per (k_l, k_s, H) pooled over seeds) or ``"topographies"``
  (``fit_topographies``, all patches pooled as one surface type);
* ``figures``: the kind of figures that apply (a :class:`roughcontact.figures.registry.FigureSpec`'s
  ``cases``: ``"grid"`` or ``"patches"``);
* ``studies``: the scene studies it can feed; ``default_boundary``: the contact solver's boundary
  unless the scene sets one; ``relative_load``: whether a contact load is relative to each
  surface's rms slope unless the scene says otherwise;
* ``check_scene(name, scene, delta, check_files)``: the validated, expanded scene (a
  ``ConfigError`` naming scene and field otherwise), and ``plan(scene)``: its cost in words.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from ...core.registry import registrar

#: The surface sources a scene can use, by name (filled by :func:`register`, in module order).
SOURCES: dict[str, type[Source]] = {}


#: Class decorator: make a class available to scenes under its ``name``.
register = registrar(SOURCES, "surface source")


class Source:
    """A surface source: the defaults every source starts from (see the module's docstring)."""

    name = ""
    key: str | None = None
    case_keys: tuple[str, ...] = ()
    stem = ""
    case_dims: tuple[str, ...] = ()
    record_key = ""
    fit = "grid"
    figures = "grid"
    surface_rules: tuple[str, ...] = ()
    studies: tuple[str, ...] = ("representativity", "contact")
    default_boundary = "periodic"
    relative_load = False
    #: Recorded settings that differ between cases by design (a patch file's path, unit, size): the
    #: aggregate keeps them per case (``setting_<key>``) without warning that cases were solved differently.
    per_case_settings: tuple[str, ...] = ()

    @classmethod
    def unexpected_settings(cls, varying) -> list[str]:
        """The keys of ``varying`` (settings that differ between cases) that do not differ by design."""
        return [key for key in varying if key not in cls.per_case_settings]

    @classmethod
    def applies(cls, scene: Mapping) -> bool:
        """Whether ``scene`` (as written or validated) takes its surfaces from this source."""
        return cls.key is not None and cls.key in scene

    @classmethod
    def check_scene(cls, name: str, scene: dict, delta: Mapping | None = None, *, check_files: bool = True) -> dict:
        """The schema-checked ``scene`` checked and expanded for this source (a new dict)."""
        raise NotImplementedError

    @classmethod
    def check_contact_files(cls, name: str, scene: Mapping) -> None:
        """What the source's files allow the validated ``contact`` block (``ConfigError`` naming the field); run
        before any job for the scene that runs. Nothing for a source without files."""

    @classmethod
    def cases(cls, scene: Mapping, study: str) -> list[dict]:
        """The cases of ``study`` in a validated scene, each ``{wildcard: value}``."""
        raise NotImplementedError

    @classmethod
    def stems(cls, scene: Mapping, study: str) -> list[str]:
        """The file stem of every case of ``study``."""
        return [cls.stem.format(**case) for case in cls.cases(scene, study)]

    @classmethod
    def batch_stems(cls, scene: Mapping, study: str) -> list[str]:
        """The file stems of the representativity jobs of ``study`` (one per case unless batched)."""
        return cls.stems(scene, study)

    @classmethod
    def case_list(cls, scene: Mapping, study: str) -> list:
        """The aggregates' ``cases`` parameter: the cases of ``study`` as plain JSON values."""
        return [list(case.values()) for case in cls.cases(scene, study)]

    @classmethod
    def names(cls, scene: Mapping) -> list[str]:
        """The named cases of a patch source's scene, sorted; [] for a source of unnamed cases."""
        return []

    @classmethod
    def plan(cls, scene: Mapping) -> list[str]:
        """What the scene's studies compute, in words (parts of :func:`roughcontact.pipeline.scenes.plan_summary`)."""
        return []


def source_of(scene: Mapping, name: str = "") -> type[Source]:
    """The source of ``scene`` (``name`` for messages): exactly one registered source applies.

    Raises :class:`roughcontact.pipeline.config.ConfigError` when several apply (two source blocks
    in one scene) or none does.
    """
    found = [cls for cls in SOURCES.values() if cls.applies(scene)]
    if len(found) == 1:
        return found[0]
    from ..config.files import ConfigError

    where = f"scene {name!r}: " if name else ""
    keys = [cls.key for cls in SOURCES.values() if cls.key]
    if not found:
        raise ConfigError(f"{where}no surface source applies; a scene takes its surfaces from one of: "
                          f"{', '.join(SOURCES)} (blocks {', '.join(keys)}, or the generator's study keys)")
    blocks = [cls.key for cls in found if cls.key]
    raise ConfigError(f"{where}takes its surfaces from {len(found)} sources at once ({', '.join(c.name for c in found)}"
                      f"{'; blocks ' + ', '.join(blocks) if blocks else ''}); a scene has one source: keep one "
                      "block and move the others' files to a scene of their own")


def for_dims(dims: Sequence[str]) -> type[Source]:
    """The first registered source whose case dimensions a dataset of dimensions ``dims`` has.

    Sources with the same case dimensions aggregate and fit alike, so the first one stands for all.
    """
    for cls in SOURCES.values():
        if cls.case_dims and set(cls.case_dims) <= set(dims):
            return cls
    raise ValueError(f"no surface source has the case dimensions of a dataset with dimensions {sorted(dims)}; "
                     f"known: {', '.join(f'{c.name} {c.case_dims}' for c in SOURCES.values())}")


def for_case(keys: Sequence[str]) -> type[Source]:
    """The first registered source whose case wildcards are ``keys`` (a job's, without ``scene``)."""
    for cls in SOURCES.values():
        if set(cls.case_keys) == set(keys):
            return cls
    raise ValueError(f"no surface source has the case wildcards {sorted(keys)}")
