"""The package's architecture, checked from its source: layers, no import cycles, small modules and functions.

The import graph is read with :mod:`ast` over ``src/roughcontact`` (every ``import`` and ``from ... import``,
those inside functions too); nothing is imported. Importing ``a.b.c`` runs the packages ``a.b`` and ``a``
first, so an import of a module counts as an import of each package above it too (those above the
importer itself excepted: they are already running), and a cycle through a package's ``__init__`` is found.

Layers, bottom to top (:data:`LAYERS`): the foundation ``core``; physics (``surfaces``, ``solver``, ``theory``,
``statistics``); ``analysis``; ``case`` (a contact case as a library object); ``pipeline`` and ``figures``;
``studies``; the package's face ``roughcontact/__init__.py`` on top. A module may import its own layer and the
layers below, never one above.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGE = "roughcontact"

#: Rank of each top-level subpackage: imports flow from a higher rank to a lower or equal one.
LAYERS = {
    "core": 0,
    "surfaces": 1,
    "solver": 1,
    "theory": 1,
    "statistics": 1,
    "analysis": 2,
    "case": 3,
    "pipeline": 4,
    "figures": 4,
    "studies": 5,
}
#: The package's face (``roughcontact/__init__.py``: the public API) sits above every layer.
FACE_RANK = max(LAYERS.values()) + 1

MAX_MODULE_LINES = 500
MAX_FUNCTION_LINES = 60
#: Modules allowed over MAX_MODULE_LINES, each with its reason.
LONG_MODULES: dict[str, str] = {
    "roughcontact.statistics.clusters": "one concept, the contact clusters of a cell: periodic labelling, each "
                                        "cluster's statistics and their per-step dataset (wrapping's bits included)",
    "roughcontact.surfaces.topography": "one concept, an instrument's file read into a height map (format, channel, "
                                        "units, undefined points, each failure's message), SurfaceTopography "
                                        "imported on first use (it imports matplotlib)",
    "roughcontact.solver.batch.cpu": "one concept, the batched iteration's fused host kernels: each compiled loop "
                                     "beside the method that calls it, the free set's indices they share",
}


# ------------------------------------------------------------------------------ the checker
def module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _resolve(module: str, is_package: bool, node: ast.ImportFrom) -> str:
    if not node.level:
        return node.module or ""
    base = module.split(".") if is_package else module.split(".")[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def ancestors(module: str) -> list[str]:
    """The packages above ``module``: ``a.b.c`` -> ``["a", "a.b"]``."""
    parts = module.split(".")
    return [".".join(parts[:i]) for i in range(1, len(parts))]


def imports_of(source: str, module: str, is_package: bool, known: set[str]) -> set[str]:
    """The modules of ``known`` that ``source`` (module ``module``) imports, anywhere in its body.

    Each imported module brings the packages above it that are not above ``module`` (their
    ``__init__`` runs first).
    """
    out = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out.update(alias.name for alias in node.names if alias.name in known)
        elif isinstance(node, ast.ImportFrom):
            target = _resolve(module, is_package, node)
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                if sub in known:  # ``from pkg import submodule``
                    out.add(sub)
                elif target in known:
                    out.add(target)
    own = set(ancestors(module))
    out |= {a for m in out for a in ancestors(m) if a in known and a not in own}
    out.discard(module)
    return out


def import_graph(sources: dict[str, tuple[str, bool]]) -> dict[str, set[str]]:
    """``{module: (source, is_package)}`` -> ``{module: modules of the set it imports}``."""
    known = set(sources)
    return {m: imports_of(src, m, pkg, known) for m, (src, pkg) in sources.items()}


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def rank(module: str, layers: dict[str, int] = LAYERS) -> int:
    parts = module.split(".")
    if len(parts) == 1:
        return max(layers.values()) + 1
    if parts[1] not in layers:
        raise KeyError(f"{module}: its folder {parts[1]!r} has no layer; add it to LAYERS")
    return layers[parts[1]]


def upward_imports(graph: dict[str, set[str]], layers: dict[str, int] = LAYERS) -> list[tuple[str, str]]:
    """Every import ``(a, b)`` from a lower layer to a higher one."""
    return sorted((a, b) for a, targets in graph.items() for b in targets if rank(b, layers) > rank(a, layers))


def long_functions(source: str, limit: int = MAX_FUNCTION_LINES) -> list[tuple[str, int]]:
    """Functions spanning over ``limit`` lines, from the ``def`` line to the last, docstring included."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            n = node.end_lineno - node.lineno + 1
            if n > limit:
                out.append((node.name, n))
    return out


def package_sources(root: Path = SRC) -> dict[str, tuple[str, bool]]:
    return {module_name(p, root): (p.read_text(encoding="utf-8"), p.name == "__init__.py")
            for p in sorted((root / PACKAGE).rglob("*.py"))}


# ------------------------------------------------------------------------------ the package
@pytest.fixture(scope="module")
def sources():
    return package_sources()


@pytest.fixture(scope="module")
def graph(sources):
    return import_graph(sources)


def test_the_graph_is_read(graph):
    # a sanity check of the reader: the face imports the solver, the solver the foundation
    assert "roughcontact.solver" in graph["roughcontact"]
    assert "roughcontact.core.quantities" in graph["roughcontact.solver.settings"]


def test_no_import_cycles(graph):
    assert cycles(graph) == []


def test_imports_flow_downward(graph):
    assert upward_imports(graph) == []


def test_every_folder_has_a_layer(graph):
    for module in graph:
        rank(module)  # raises for a folder not in LAYERS


def test_modules_are_small(sources):
    long = {m: src.count("\n") for m, (src, _) in sources.items()
            if src.count("\n") > MAX_MODULE_LINES and m not in LONG_MODULES}
    assert long == {}


def test_functions_are_short(sources):
    long = {m: found for m, (src, _) in sources.items() if (found := long_functions(src))}
    assert long == {}


#: Where a ``length`` may be asked whether it is a float ``L`` or a pair ``(Lx, Ly)``: the cell alone (the
#: solver's check of the user's arguments parses it with ``check_length``).
LENGTH_FORM_MODULES = {"roughcontact.core.cell"}


def _is_length(node: ast.AST) -> bool:
    """``length`` or ``<anything>.length``."""
    return (isinstance(node, ast.Name) and node.id == "length") or (
        isinstance(node, ast.Attribute) and node.attr == "length")


def length_form_branches(source: str) -> list[int]:
    """Lines asking a ``length`` its form: ``np.ndim(length)``, ``isinstance(length, ...)``, ``len(length)``
    (``length`` a name or an attribute ``x.length``); :class:`roughcontact.core.cell.Cell` answers that."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if not (isinstance(node, ast.Call) and node.args and _is_length(node.args[0])):
            continue
        f = node.func
        if (isinstance(f, ast.Attribute) and f.attr == "ndim") or (
                isinstance(f, ast.Name) and f.id in {"isinstance", "len", "ndim"}):
            found.append(node.lineno)
    return sorted(found)


def test_only_the_cell_asks_a_length_its_form(sources):
    # issue 47: a float L or a pair (Lx, Ly) is converted to a Cell once, and the cell is asked after that
    found = {m: lines for m, (src, _) in sources.items()
             if m not in LENGTH_FORM_MODULES and (lines := length_form_branches(src))}
    assert found == {}


# ------------------------------------------------------------------------------ effects are asked, not named
#: Python outside the package that the same rules cover: the workflow's job scripts.
SCRIPTS = SRC.parent / "workflow" / "scripts"
#: Snakemake's rule files (not Python: searched as text).
RULES = [SRC.parent / "Snakefile", *sorted((SRC.parent / "workflow" / "rules").glob("*.smk"))]
#: The library's layers: below the pipeline, they know no scene's vocabulary.
LIBRARY_LAYERS = ("core", "surfaces", "solver", "theory", "statistics", "analysis", "case")
#: Keys of a scene's blocks the library never looks up (an effect's ``from_config`` reads its own block's keys).
SCENE_KEYS = frozenset({"load", "p_max", "relative_to", "target_area", "n_steps", "solver", "outputs", "effects",
                        "grid", "seeds", "surface"})
#: The name that asked a contact block whether it was adhesive (issue 64.3: the effects declare it).
RETIRED_NAMES = frozenset({"is_adhesive"})


def script_sources() -> dict[str, tuple[str, bool]]:
    return {f"workflow.scripts.{p.stem}": (p.read_text(encoding="utf-8"), False) for p in sorted(SCRIPTS.glob("*.py"))}


def effect_modules() -> dict[str, str]:
    """Each registered effect's name -> the module that defines it (``roughcontact.solver.effects.<module>``)."""
    from roughcontact.solver.effects import EFFECTS

    return {name: effect.__module__ for name, effect in EFFECTS.items()}


def names_used(source: str, names) -> list[int]:
    """Lines that define, import or use one of ``names`` (a name, an attribute, a def, an import alias)."""
    found = []
    for node in ast.walk(ast.parse(source)):
        used = (node.id if isinstance(node, ast.Name) else node.attr if isinstance(node, ast.Attribute)
                else node.name if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) else None)
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            used = next((a.name.split(".")[-1] for a in node.names if a.name.split(".")[-1] in names), None)
        if used in names:
            found.append(node.lineno)
    return sorted(found)


def string_literals(source: str, values) -> list[tuple[int, str]]:
    """``(line, value)`` of every string constant equal to one of ``values`` (f-strings' constant parts too)."""
    return sorted((node.lineno, node.value) for node in ast.walk(ast.parse(source))
                  if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in values)


def key_lookups(source: str, keys) -> list[tuple[int, str]]:
    """``(line, key)`` of every lookup of one of ``keys`` by a constant: ``x["key"]``, ``x.get("key", ...)``
    (``pop`` and ``setdefault`` too)."""
    found = []
    for node in ast.walk(ast.parse(source)):
        key = None
        if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant):
            key = node.slice.value
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.args
              and node.func.attr in {"get", "pop", "setdefault"} and isinstance(node.args[0], ast.Constant)):
            key = node.args[0].value
        if isinstance(key, str) and key in keys:
            found.append((node.lineno, key))
    return sorted(found)


def test_no_module_asks_whether_a_block_is_adhesive(sources):
    # the pipeline asks the effects what they need and give (Effect.keeps_elastic_law, .figures, ...)
    found = {m: lines for m, (src, _) in {**sources, **script_sources()}.items()
             if (lines := names_used(src, RETIRED_NAMES))}
    found |= {p.name: [i for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
                       if any(name in line for name in RETIRED_NAMES)] for p in RULES}
    assert {m: lines for m, lines in found.items() if lines} == {}


def test_effect_names_are_written_only_in_their_own_module(sources):
    # an effect's name is the scene's data (a key of contact.effects), never a literal the code tests for: a new
    # effect declares what it needs and gives, and no planner, rule, figure or report module names it
    owners = effect_modules()
    assert {"adhesion", "plasticity"} <= set(owners)
    found = {}
    for module, (src, _) in {**sources, **script_sources()}.items():
        hits = [(line, value) for line, value in string_literals(src, set(owners)) if owners[value] != module]
        if hits:
            found[module] = hits
    assert found == {}


def test_the_library_looks_up_no_scene_key(sources):
    # the scene's vocabulary (load, p_max, relative_to, solver, effects, ...) stops at the pipeline
    # (roughcontact.pipeline.case.contact_case, contact_effects): effects and rules below it take numbers
    found = {m: hits for m, (src, _) in sources.items()
             if m.split(".")[1:2] and m.split(".")[1] in LIBRARY_LAYERS and (hits := key_lookups(src, SCENE_KEYS))}
    assert found == {}


# ------------------------------------------------------------------------------ one contact path
def workflow_outputs() -> dict[str, list[str]]:
    """Every rule of the shipped workflow and its output patterns, as Snakemake parses them."""
    from snakemake.api import SnakemakeApi
    from snakemake.settings.types import ConfigSettings, OutputSettings, ResourceSettings, StorageSettings

    with SnakemakeApi(OutputSettings(quiet={"all"})) as api:
        workflow = api.workflow(resource_settings=ResourceSettings(), config_settings=ConfigSettings(),
                                storage_settings=StorageSettings(), snakefile=SRC.parent / "Snakefile",
                                workdir=SRC.parent)
        return {rule.name: [str(out) for out in rule.output] for rule in workflow._workflow.rules}


def test_scene_vocabulary_becomes_a_case_in_one_module_only():
    # issue 64.1: the job scripts take their cases from roughcontact.pipeline.case (contact_case, accuracy_case)
    found = {m: lines for m, (src, _) in script_sources().items()
             if (lines := names_used(src, {"ContactCase", "LoadSchedule", "SolverSettings"}))}
    assert found == {}


def test_one_rule_writes_contact_files():
    # issue 64.2: one case, a batch or one case over MPI ranks is one contact job of one rule, each case's file
    # written once (no batch or MPI job whose file another job copies)
    outputs = workflow_outputs()
    writers = {rule: outs for rule, outs in outputs.items() if any("/contact/" in out for out in outs)}
    assert list(writers) == ["contact"] and len(writers["contact"]) == 1, writers
    assert not [rule for rule in outputs if rule.startswith("contact") and rule != "contact"]


# ------------------------------------------------------------------------------ the checker can fail
def test_checker_finds_effect_names_and_scene_keys():
    source = ('from .cases import is_adhesive\nif is_adhesive(b): pass\nx = cases.is_adhesive\n'
              'def is_adhesive(b): return "adhesion" in b["effects"]\n'
              'y = f"effects.{n}" + "plasticity"\nz = c.get("load", {}).pop("p_max")\nw = d["hardness"]\n'
              'v = "adhesive contact"\nu = {"load": 1}\n')
    assert names_used(source, RETIRED_NAMES) == [1, 2, 3, 4]
    assert string_literals(source, {"adhesion", "plasticity"}) == [(4, "adhesion"), (5, "plasticity")]
    assert key_lookups(source, SCENE_KEYS) == [(4, "effects"), (6, "load"), (6, "p_max")]


def test_checker_finds_a_length_form_branch():
    source = ("a = np.ndim(length) == 0\nb = numpy.ndim(s.length)\nc = isinstance(length, tuple)\n"
              "d = len(self.length)\ne = np.ndim(shape)\nf = cell.square\ng = len(lengths)\n")
    assert length_form_branches(source) == [1, 2, 3, 4]


def private_imports(sources: dict[str, tuple[str, bool]]) -> set[tuple[str, str, str]]:
    """``(importer, module, name)`` for every import of another module's underscore name.

    ``module`` is the module the name is imported from (relative imports resolved); a name of the
    importer's own module does not count, nor dunder names.
    """
    found = set()
    for module, (source, is_package) in sources.items():
        for node in ast.walk(ast.parse(source)):
            if not isinstance(node, ast.ImportFrom):
                continue
            target = _resolve(module, is_package, node)
            for alias in node.names:
                if alias.name.startswith("_") and not alias.name.startswith("__") and target != module:
                    found.add((module, target, alias.name))
    return found


def test_no_imports_of_private_names(sources):
    # a name another module needs is public, with a docstring; or the two modules are one concept
    assert sorted(private_imports(sources)) == []


def sys_modules_lookups(source: str) -> list[int]:
    """Lines that read ``sys.modules`` (or import ``modules`` from ``sys``): state found by name, not passed."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if (isinstance(node, ast.Attribute) and node.attr == "modules" and isinstance(node.value, ast.Name)
                and node.value.id == "sys"):
            found.append(node.lineno)
        elif isinstance(node, ast.ImportFrom) and node.module == "sys" and any(a.name == "modules" for a in node.names):
            found.append(node.lineno)
    return found


def test_no_sys_modules_lookups(sources):
    # a setting reaches the code that reads it as an argument or a field, never through sys.modules
    found = {m: lines for m, (src, _) in sources.items() if (lines := sys_modules_lookups(src))}
    assert found == {}


def test_checker_finds_sys_modules():
    assert sys_modules_lookups("import sys\nx = sys.modules[__package__].X\n") == [2]
    assert sys_modules_lookups("from sys import modules\n") == [1]
    assert sys_modules_lookups("import sys\nsys.path\n") == []


def test_checker_finds_a_cycle_through_a_package():
    # config/__init__ imports config.scenes, which imports sources; a source imports config.files, which
    # runs config/__init__ first: a cycle, though no module names another's directly in both directions
    sources = {
        "roughcontact.pipeline": ("", True),
        "roughcontact.pipeline.config": ("from .scenes import validate\n", True),
        "roughcontact.pipeline.config.files": ("", False),
        "roughcontact.pipeline.config.scenes": ("def f():\n    from ..sources import source_of\n", False),
        "roughcontact.pipeline.sources": ("from .base import source_of\n", True),
        "roughcontact.pipeline.sources.base": ("from ..config.files import ConfigError\n", False),
    }
    g = import_graph(sources)
    assert g["roughcontact.pipeline.sources.base"] == {"roughcontact.pipeline.config.files",
                                                       "roughcontact.pipeline.config"}
    assert "roughcontact.pipeline" not in g["roughcontact.pipeline.sources.base"]  # its own package: running
    assert cycles(g) == [["roughcontact.pipeline.config", "roughcontact.pipeline.config.scenes",
                          "roughcontact.pipeline.sources", "roughcontact.pipeline.sources.base"]]


def test_checker_finds_a_cycle_and_an_upward_import():
    sources = {
        "roughcontact": ("from .studies import page\n", True),
        "roughcontact.core.units": ("from ..analysis.fit import grid\n", False),  # upward, and a cycle
        "roughcontact.analysis.fit": ("", True),
        "roughcontact.analysis.fit.grid": ("def f():\n    from ...core import units\n", False),  # lazy: still read
        "roughcontact.studies.page": ("import roughcontact.core.units\n", False),
        "roughcontact.core": ("", True),
    }
    g = import_graph(sources)
    # each import brings the packages above the imported module (their __init__ runs first)
    assert g["roughcontact.core.units"] == {"roughcontact.analysis.fit.grid", "roughcontact.analysis.fit"}
    assert g["roughcontact.analysis.fit.grid"] == {"roughcontact.core.units", "roughcontact.core"}
    assert cycles(g) == [["roughcontact.analysis.fit.grid", "roughcontact.core.units"]]
    assert upward_imports(g) == [("roughcontact.core.units", "roughcontact.analysis.fit"),
                                 ("roughcontact.core.units", "roughcontact.analysis.fit.grid")]
    with pytest.raises(KeyError, match="no layer"):
        rank("roughcontact.attic.old")


def test_checker_counts_whole_functions():
    body = "".join(f"    x{i} = {i}\n" for i in range(59))
    assert long_functions(f"def f():\n{body}") == []
    assert long_functions(f'def f():\n    """Doc."""\n{body}') == [("f", 61)]
    assert long_functions(f"def outer():\n    def inner():\n{body.replace('    ', '        ')}        pass\n"
                          "    return inner\n") == [("outer", 63), ("inner", 61)]


def test_checker_finds_a_private_import():
    sources = {"roughcontact.a": ("from .b import _hidden, shown\nfrom . import b\n", False),
               "roughcontact.b": ("def _hidden(): pass\n_own = 1\nfrom .b import _own\n", False)}
    assert private_imports(sources) == {("roughcontact.a", "roughcontact.b", "_hidden")}
