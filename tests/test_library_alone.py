"""The library stands alone: its layers import without snakemake and without matplotlib.

``core``, ``surfaces``, ``solver``, ``theory``, ``statistics``, ``analysis`` and ``case`` are the solver library; the
pipeline (Snakemake) and the figures (matplotlib) sit above them (tests/test_architecture.py). A fresh
interpreter in which both are made unimportable (a :data:`sys.meta_path` finder raising ImportError, as
if they were not installed) imports every module of those layers.
"""

import subprocess
import sys
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
LIBRARY_LAYERS = ("core", "surfaces", "solver", "theory", "statistics", "analysis", "case")
BLOCKED = ("snakemake", "matplotlib")

#: Run in a subprocess: block BLOCKED, import each module named on the command line, print what failed.
PROBE = """
import importlib, importlib.abc, sys, traceback

BLOCKED = {blocked!r}


class Refuse(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in BLOCKED:
            raise ImportError(f"{{name}} is made unimportable by tests/test_library_alone.py")
        return None


sys.meta_path.insert(0, Refuse())
failed = []
for module in sys.argv[1:]:
    try:
        importlib.import_module(module)
    except Exception:
        failed.append(module + ": " + traceback.format_exc().strip().splitlines()[-1])
loaded = sorted(m for m in sys.modules if m.split(".")[0] in BLOCKED)
print("\\n".join(failed + [f"loaded: {{m}}" for m in loaded]))
"""


def library_modules(src: Path = SRC) -> list[str]:
    """Every module of the library's layers, by dotted name."""
    out = []
    for layer in LIBRARY_LAYERS:
        for path in sorted((src / "roughcontact" / layer).rglob("*.py")):
            parts = list(path.relative_to(src).with_suffix("").parts)
            if parts[-1] == "__main__":
                continue
            if parts[-1] == "__init__":
                parts.pop()
            out.append(".".join(parts))
    return out


def probe(modules: list[str], blocked=BLOCKED) -> str:
    proc = subprocess.run([sys.executable, "-c", PROBE.format(blocked=tuple(blocked)), *modules],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.strip()


def test_every_library_module_is_listed():
    modules = library_modules()
    assert "roughcontact.surfaces.topography" in modules and "roughcontact.analysis.fit" in modules
    assert not any(m.startswith(("roughcontact.pipeline", "roughcontact.figures")) for m in modules)


def test_the_library_imports_without_snakemake_and_matplotlib():
    assert probe(library_modules()) == ""


def test_the_probe_sees_a_blocked_import():
    # the finder refuses what it should: the pipeline imports snakemake, the figures matplotlib
    out = probe(["roughcontact.pipeline.targets", "roughcontact.figures.style", "roughcontact.core.quantities"])
    assert "roughcontact.pipeline.targets: ImportError: snakemake" in out
    assert "roughcontact.figures.style: ImportError: matplotlib" in out
    assert "roughcontact.core.quantities" not in out
