"""Every command and code block of README.md, config/README.md and docs/*.md is exercised here.

The markdown is parsed, not copied: fenced ```bash, ```python and ```yaml blocks, and inline
`code` that starts with `snakemake`, `make`, `pip`, `python` or `. ` (outside fences). Each
item must match a row of COMMANDS (commands, also each command of a bash block) or BLOCKS
(python and yaml blocks); an item no row matches fails its test, so a new documented command
needs a handler here before CI passes.

What the handlers check:
- snakemake: a dry run (`-n` added) in a copy of the workflow with the shipped config and every
  documented scene file (a yaml block whose first line is `# NAME.yaml`), exit 0, each file
  target planned; `--unlock` and `--lint` run for real. `-f TARGET` and `--report` need finished
  results: they run on a small finished scene (marked slow). `--rerun-triggers ...` (rerunning
  one case with other settings): its whole bash block runs for real on a small finished scene
  after a config edit; only the forced case is solved again, the next run plans nothing, and a
  restored config reruns only that case (marked slow).
- make: `make -n TARGET` succeeds (the target exists; nothing is run, so `make test` does not
  recurse). pip: the extra named in `pip install -e '.[X]'` exists in pyproject.toml.
  `. .venv/bin/activate`: the Makefile's VENV is `.venv` and it is made by `python -m venv`.
- `python -m roughcontact.pipeline.config FILE`: exit 0 in the workflow copy that holds the scene files.
- `mpiexec -n R python -m roughcontact.solver.mpi ...` (or `srun python -m ...`): its arguments parse.
- python: run in a subprocess in an empty directory. yaml: parses; an excerpt of shipped scenes
  equals config/config.yaml's; a SLURM profile copy has only
  the shipped profile's keys and values (plus the site's partition and account), and the command
  in its first-line comment dry-runs with it; a scene file must be used by a documented
  `--configfile` command.
Every `roughcontact.x.y` and `file.py` that the README files and docs/ name exists, and README's layout
rows name their packages' modules (the last two tests).
Dry runs of the `paper` scene (its full DAG, thousands of jobs), the finished-scene commands and the
python block (a 512^2 solve) are marked slow: `make test` runs them, `make test-fast` does not.
"""
from __future__ import annotations

import copy
import importlib.util
import os
import re
import shlex
import shutil
import subprocess
import sys
import textwrap
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import pytest
import xarray as xr
import yaml

from conftest import REPO, copy_workflow, run_snakemake
from test_workflow import PAPER_JOBS, _jobs

DOCS = ("README.md", "config/README.md",
        *(f"docs/{name}.md" for name in ("cluster", "representative", "accuracy", "solver")))
COMMAND_START = re.compile(r"^(snakemake|make|pip|python)(\s|$)|^\.\s")
SLOW_COMMAND = re.compile(r"scene=paper\b")  # the full paper DAG: thousands of jobs, slow on a busy machine
SLURM_PROFILE = REPO / "profiles" / "slurm" / "config.yaml"
USER_RESOURCES = {"slurm_partition", "slurm_account"}  # the site's own, commented out in the shipped profile
PYTHON_BLOCK_TIMEOUT_S = 600  # the README's snippet takes ~15 s (N=512, 30 steps) on 2 busy cores


# ------------------------------------------------------------------------------------- parsing
@dataclass
class Item:
    kind: str  # "command", "python" or "yaml"
    text: str
    where: list[str] = field(default_factory=list)  # "README.md:27", every place it appears

    @property
    def id(self) -> str:
        first = self.text.splitlines()[0] if self.text.strip() else ""
        return f"{self.where[0]}:{self.kind}:{first[:70]}"


def _commands_of_bash(text: str) -> list[str]:
    """Commands of a bash block: comments dropped, continuation lines joined, split at && ; ||."""
    commands = []
    for line in text.replace("\\\n", " ").splitlines():
        tokens = shlex.split(line, comments=True)
        current: list[str] = []
        for tok in [*tokens, "&&"]:
            if tok in ("&&", "||", ";"):
                if current:
                    commands.append(shlex.join(current))
                current = []
            else:
                current.append(tok)
    return commands


def parse_docs(docs=DOCS) -> list[Item]:
    items: dict[tuple[str, str], Item] = {}

    def add(kind, text, where):
        items.setdefault((kind, text), Item(kind, text)).where.append(where)

    for doc in docs:
        lines = (REPO / doc).read_text().splitlines()
        i = 0
        while i < len(lines):
            fence = re.match(r"^\s*```\s*(\S*)", lines[i])
            if fence:
                lang, start = fence.group(1).lower(), i + 1
                i += 1
                while i < len(lines) and not re.match(r"^\s*```\s*$", lines[i]):
                    i += 1
                body = "\n".join(lines[start:i]) + "\n"
                where = f"{doc}:{start}"
                if lang in ("bash", "sh", "shell", "console"):
                    for cmd in _commands_of_bash(body):
                        add("command", cmd, where)
                else:
                    add(lang or "unlabelled", body, where)
            else:
                for code in re.findall(r"`([^`\n]+)`", lines[i]):
                    if COMMAND_START.match(code.strip()):
                        add("command", code.strip(), f"{doc}:{i + 1}")
            i += 1
    return list(items.values())


def _yaml_header(text: str) -> tuple[str | None, str]:
    """(file name, rest) from a first line like `# my_scene.yaml` or `# path/config.yaml -> cmd`."""
    m = re.match(r"^#\s*(\S+\.ya?ml)\b\s*(?:->\s*(.*))?$", text.splitlines()[0].strip()) if text.strip() else None
    return (m.group(1), (m.group(2) or "").strip()) if m else (None, "")


def _is_profile(name: str | None) -> bool:
    return name is not None and Path(name).name == "config.yaml" and "profiles" in Path(name).parts


def scene_files(items) -> dict[str, str]:
    """Documented scene files (yaml blocks headed `# NAME.yaml`), by name."""
    files = {}
    for it in items:
        name, _ = _yaml_header(it.text) if it.kind == "yaml" else (None, "")
        if name and not _is_profile(name):
            assert name not in files or files[name] == it.text, f"two different blocks both named {name}"
            files[name] = it.text
    return files


ITEMS = parse_docs()
SCENE_FILES = scene_files(ITEMS)


# ------------------------------------------------------------------------------------- helpers
def _ok(res, what: str):
    assert res.returncode == 0, (f"{what} exited with status {res.returncode}\n--- stdout (end)\n"
                                 f"{res.stdout[-3000:]}\n--- stderr (end)\n{res.stderr[-3000:]}")


def _args(cmd: str) -> list[str]:
    args = shlex.split(cmd)
    assert args[0] == "snakemake", cmd
    return args[1:]


def _dry(args: list[str]) -> list[str]:
    return args if {"-n", "--dry-run", "--dryrun"} & set(args) else ["-n", *args]


def _file_targets(args: list[str]) -> list[str]:
    return [a for a in args if a.startswith("results/")]


def _placeholders(args: list[str], ctx) -> list[str]:
    """`--config scene=NAME` in the prose means any scene: the shipped default."""
    return [a.replace("scene=NAME", f"scene={ctx.default_scene}") for a in args]


def _slurm_plugin() -> bool:
    return importlib.util.find_spec("snakemake_executor_plugin_slurm") is not None


def _profile_dry_run(wd: Path, args: list[str], env=None):
    # A dry run plans the jobs a profile would submit; without the `slurm` extra installed the
    # executor cannot be loaded, so the dry-run executor stands in (the profile's other keys apply).
    extra = [] if _slurm_plugin() else ["--executor", "dryrun"]
    return run_snakemake(wd, *_dry(args), *extra, env=env)


class Context:
    """Lazily built shared state: one workflow copy for dry runs, one finished small scene."""

    def __init__(self, tmp_path_factory):
        self._factory = tmp_path_factory
        self._workflow = None
        self._finished = None
        self._dry_runs = {}
        with open(REPO / "config" / "config.yaml") as fh:
            self.shipped = yaml.safe_load(fh)
        self.default_scene = self.shipped["scene"]

    def workflow(self) -> Path:
        """A copy of the workflow with the shipped config and every documented scene file."""
        if self._workflow is None:
            wd = copy_workflow(self._factory.mktemp("docs-workflow"))
            for name, text in SCENE_FILES.items():
                (wd / name).write_text(text)
            self._workflow = wd
        return self._workflow

    def dry_run(self, args: list[str]):
        """A dry run in the shared copy; commands that plan the same (they differ only in -j) run once."""
        key = " ".join(a for a in _dry(args) if not re.fullmatch(r"-j\d*|--cores=?\d*|--jobs=?\d*|-n", a))
        key = key.replace(f"--config scene={self.default_scene}", "").strip()  # the default anyway
        if key not in self._dry_runs:
            self._dry_runs[key] = run_snakemake(self.workflow(), *_dry(args))
        return self._dry_runs[key]

    def finished(self) -> Path:
        """A fresh copy of a finished small scene named like the default (targets in the README)."""
        if self._finished is None:
            wd = copy_workflow(self._factory.mktemp("docs-finished"), self._small_scene())
            _ok(run_snakemake(wd, "-j2"), "the small scene's run")
            self._finished = wd
        dest = self._factory.mktemp("docs-finished-copy")
        shutil.copytree(self._finished, dest, dirs_exist_ok=True, symlinks=True)  # keeps mtimes
        return dest

    def _small_scene(self) -> dict:
        # The README's rerun target is results/demo/contact/kl16_ks32_H0.84_s2.nc: a small
        # `demo` with that case among three (N=64: k_s = 32 is Nyquist, allowed).
        cfg = copy.deepcopy(self.shipped)
        cfg["scene"] = self.default_scene
        cfg["scenes"] = {self.default_scene: {
            "description": "tests/test_docs.py: three small contact cases",
            "contact": {
                "surface": {"N": 64, "L": 1.0, "rms_slope": 0.1},
                "grid": {"k_l": ["16"], "k_s": ["32"], "H": ["0.84"]},
                "seeds": 3,
                "load": {"p_max": 0.01, "n_steps": 12},
                "solver": {"e_star": 1.0, "tol": 1e-8, "max_iter": 10000},
            },
            "fit": {"window": [0.01, 0.3], "n_boot": 20, "rng_seed": 2012},
        }}
        return cfg


@pytest.fixture(scope="module")
def ctx(tmp_path_factory):
    return Context(tmp_path_factory)


# ------------------------------------------------------------------------------------- handlers
def snakemake_dry_run(cmd, ctx):
    args = _placeholders(_args(cmd), ctx)
    res = ctx.dry_run(args)
    _ok(res, f"`snakemake {shlex.join(_dry(args))}` (dry run of `{cmd}`)")
    for target in _file_targets(args):
        assert target in res.stdout, f"the dry run of `{cmd}` does not plan {target}:\n{res.stdout[-3000:]}"


def snakemake_for_real(cmd, ctx):
    """Cheap commands that change nothing but the lock (--unlock) or only read (--lint)."""
    res = run_snakemake(ctx.workflow(), *_placeholders(_args(cmd), ctx))
    _ok(res, f"`{cmd}`")


def snakemake_profile(cmd, ctx):
    args = _placeholders(_args(cmd), ctx)
    _ok(_profile_dry_run(ctx.workflow(), args), f"the dry run of `{cmd}`")


def snakemake_force_one(cmd, ctx):
    """`-f TARGET` on finished results: that one contact job, then only what depends on it."""
    args = _args(cmd)
    targets = _file_targets(args)
    assert len(targets) == 1 and "/contact/" in targets[0], f"expected one contact file in `{cmd}`"
    wd = ctx.finished()
    before = {p: p.read_bytes() for p in (wd / "results").rglob("contact/*.nc")}
    assert len(before) == 3
    res = run_snakemake(wd, *_dry(args))
    _ok(res, f"the dry run of `{cmd}`")
    jobs = _jobs(res.stdout)
    assert jobs == {"contact": 1}, f"`{cmd}` must plan exactly that one contact job, plans {jobs}"
    _ok(run_snakemake(wd, *args), f"`{cmd}`")
    after = {p: p.read_bytes() for p in before}
    assert after == before, "the forced rerun must write the same bytes"
    res = run_snakemake(wd, "-n")
    _ok(res, "`snakemake -n` after the forced rerun")
    upstream = {"contact", "surface", "surface_rep", "representativity", "aggregate_representativity"}
    again = _jobs(res.stdout)
    assert not upstream & set(again), (f"after `{cmd}` only jobs downstream of that case may be "
                                       f"outdated, but `snakemake -n` plans {again}")


def _bash_block_of(cmd: str) -> list[str]:
    """The commands, in order, of the first documented bash block that holds ``cmd``."""
    for doc in DOCS:
        text = (REPO / doc).read_text()
        for body in re.findall(r"^\s*```(?:bash|sh|shell|console)\s*\n(.*?)^\s*```\s*$", text, re.M | re.S):
            commands = _commands_of_bash(body)
            if cmd in commands:
                return commands
    raise AssertionError(f"`{cmd}` is in no documented bash block")


def snakemake_rerun_edited(cmd, ctx):
    """Rerunning one case with other settings, as documented: the config edited (the scene's
    contact.solver.tol), then every command of the block that holds ``cmd``, in order, on a
    finished small scene. Only the forced case is solved again, the aggregate records which case
    had which tol, the same command then plans nothing, and once the config is restored a plain
    dry run plans that one case (and what follows) only."""
    commands = _bash_block_of(cmd)
    forced = [c for c in commands if re.search(r"\s(-f|--force)\s", c)]
    assert len(forced) == 1 and commands.index(forced[0]) < commands.index(cmd), (
        f"the block of `{cmd}` must force one file first: {commands}")
    target = _file_targets(_args(forced[0]))[0]
    wd = ctx.finished()
    config = wd / "config" / "config.yaml"
    shipped = config.read_text()
    cfg = yaml.safe_load(shipped)
    cfg["scenes"][ctx.default_scene]["contact"]["solver"]["tol"] = 1e-9
    config.write_text(yaml.safe_dump(cfg, sort_keys=False))
    files = sorted((wd / "results").rglob("contact/*.nc"))
    assert len(files) == 3 and (wd / target) in files

    def state():
        return {str(p.relative_to(wd)): (p.stat().st_mtime_ns, p.read_bytes()) for p in files}

    before = state()
    for command in commands:
        _ok(run_snakemake(wd, *_args(command)), f"`{command}` after editing the config")
    after = state()
    assert {p for p in before if after[p] != before[p]} == {target}, "only the forced case may be solved again"
    with xr.open_dataset(wd / "results" / ctx.default_scene / "aggregate" / "contact.nc") as agg:
        tol = {int(s): agg["setting_solver_tol"].sel(seed=s).item() for s in agg["seed"].values}
    seed = int(re.search(r"_s(\d+)\.nc$", target).group(1))
    assert tol == {s: 1e-9 if s == seed else 1e-8 for s in tol}, f"the aggregate's per-case tol: {tol}"
    res = run_snakemake(wd, *_dry(_args(cmd)))
    _ok(res, f"`{cmd}` again")
    assert "Nothing to be done" in res.stdout + res.stderr, f"`{cmd}` again plans:\n{res.stdout[-3000:]}"
    config.write_text(shipped)
    res = run_snakemake(wd, "-n")
    _ok(res, "`snakemake -n` with the config restored")
    assert _jobs(res.stdout).get("contact") == 1 and target in res.stdout, (
        f"with the config restored only {target} is solved again, but `snakemake -n` plans {_jobs(res.stdout)}")


def snakemake_report(cmd, ctx):
    args = _args(cmd)
    wd = ctx.finished()
    _ok(run_snakemake(wd, *args), f"`{cmd}` on a finished scene")
    out = args[args.index("--report") + 1]
    assert (wd / out).stat().st_size > 10_000, f"`{cmd}` wrote a near-empty {out}"


def _on_finished(cmd, ctx) -> subprocess.CompletedProcess:
    """``python -m ...`` run in the finished small scene's folder; it must exit 0."""
    res = subprocess.run([sys.executable, *shlex.split(cmd)[1:]], cwd=ctx.finished(), capture_output=True,
                         text=True, timeout=120)
    _ok(res, f"`{cmd}` on a finished scene")
    return res


def python_runcost(cmd, ctx):
    """``python -m roughcontact.pipeline.runcost results/<scene>`` on a finished small scene: a row per rule."""
    res = _on_finished(cmd, ctx)
    assert re.search(r"^\| contact \| 3 \| ", res.stdout, re.M), (
        f"`{cmd}`: no row for the 3 contact jobs:\n{res.stdout}")
    # every job of the current code logs its exact cost: no total is a sampled lower bound
    assert "≥" not in res.stdout, f"`{cmd}`: jobs without their exact cost line:\n{res.stdout}"


def python_progress(cmd, ctx):
    """``python -m roughcontact.pipeline.progress results/<scene>`` on a finished small scene: every planned
    job done."""
    res = _on_finished(cmd, ctx)
    assert re.search(r"^scene '[\w-]+': (\d+) of \1 jobs done \(contact (\d+) of \2\), all$", res.stdout, re.M), (
        f"`{cmd}`: the finished scene is not reported done:\n{res.stdout}")


def python_adopt(cmd, ctx):
    """``python -m roughcontact.pipeline.adopt results/<a> --scene <b>`` between two small runs of the shipped scenes.

    Two of b's planned cases exist in a (as its contact rule writes them, no solve), one of them
    also in b: the command adopts the other.
    """
    from roughcontact.pipeline import adopt
    from roughcontact.pipeline.scenes import validate_config
    from test_adopt import _case_file

    args = shlex.split(cmd)[3:]
    source, target = Path(args[0]), args[args.index("--scene") + 1]
    wd = ctx._factory.mktemp("docs-adopt")
    (wd / "config").mkdir()
    shutil.copy(REPO / "config" / "config.yaml", wd / "config" / "config.yaml")
    scene = validate_config({**ctx.shipped, "scene": target})["scenes"][target]
    parameters = adopt.expected_parameters(scene)
    for i, (name, case) in enumerate(sorted(adopt.planned_files(scene).items())[:2]):
        _case_file(wd / source / "contact" / name, case, scene=source.name, parameters=parameters)
        if i == 0:
            _case_file(wd / "results" / target / "contact" / name, case, scene=target, parameters=parameters)
    res = subprocess.run([sys.executable, *shlex.split(cmd)[1:]], cwd=wd, capture_output=True, text=True,
                         timeout=120)
    _ok(res, f"`{cmd}` between two small runs")
    assert "adopted 1 case(s)" in res.stdout, f"`{cmd}`: {res.stdout}"


def python_config(cmd, ctx):
    """``python -m roughcontact.pipeline.config FILE ...`` in the workflow copy holding the documented scene files."""
    res = subprocess.run([sys.executable, *shlex.split(cmd)[1:]], cwd=ctx.workflow(), capture_output=True, text=True,
                         timeout=120)
    _ok(res, f"`{cmd}` in a workflow copy with the documented scene files")
    assert "roughcontact: scene '" in res.stdout and " plans " in res.stdout, res.stdout


def make_target(cmd, ctx):
    args = shlex.split(cmd)[1:]
    res = subprocess.run(["make", "-n", *args], cwd=REPO, capture_output=True, text=True, timeout=120)
    _ok(res, f"`make -n {shlex.join(args)}` (is the target in the Makefile?)")


def pip_extra(cmd, ctx):
    m = re.fullmatch(r"pip install -e '?\.\[([\w,-]+)\]'?", cmd)
    assert m, f"only `pip install -e '.[EXTRA]'` is documented and handled, not `{cmd}`"
    with open(REPO / "pyproject.toml", "rb") as fh:
        extras = tomllib.load(fh)["project"]["optional-dependencies"]
    for extra in m.group(1).split(","):
        assert extra in extras, f"`{cmd}`: pyproject.toml has no extra {extra!r} (has {sorted(extras)})"


def mpi_command(cmd, ctx):
    """``mpiexec -n R`` / ``srun`` + ``python -m roughcontact.solver.mpi ...``: its arguments parse (nothing runs:
    the documented runs are N = 8192 and larger; tests/test_solver_mpi.py runs the command line)."""
    from roughcontact.solver.mpi.__main__ import parser

    args = shlex.split(cmd)
    start = args.index("-m") + 2
    assert args[start - 1] == "roughcontact.solver.mpi", cmd
    parser().parse_args(args[start:])


def activate_venv(cmd, ctx):
    m = re.fullmatch(r"\.\s+(\S+)/bin/activate", cmd)
    assert m, cmd
    makefile = (REPO / "Makefile").read_text()
    venv = re.search(r"^VENV\s*\??=\s*(\S+)\s*$", makefile, re.M)
    assert venv and venv.group(1) == m.group(1), f"`{cmd}`, but the Makefile's VENV is {venv and venv.group(1)}"
    assert re.search(r"-m venv \$\(VENV\)", makefile), "the Makefile does not create $(VENV) with `python -m venv`"
    if sys.prefix != sys.base_prefix:  # running in a venv: it has the layout the command needs
        assert (Path(sys.prefix) / "bin" / "activate").is_file()


def python_slab_wisdom(cmd, ctx):
    """``python -c "...write_wisdom(...)"`` of the MPI slabs: the code runs with ``write_wisdom`` replaced by a check
    that its arguments bind to the real signature and name problems ``slab_problems`` can plan (running it would
    measure plans into the installed package's wisdom file)."""
    code = shlex.split(cmd)[2]
    check = textwrap.dedent("""
        import inspect
        import roughcontact.solver.mpi.slabs as slabs
        real = slabs.write_wisdom
        def write_wisdom(*args, **kwargs):
            bound = inspect.signature(real).bind(*args, **kwargs)
            bound.apply_defaults()
            a = bound.arguments
            assert slabs.slab_problems(a["sizes"], a["ranks"], a["tiles"]), "no slab problem to plan"
            print("bound", dict(a))
        slabs.write_wisdom = write_wisdom
    """)
    res = subprocess.run([sys.executable, "-c", check + code], capture_output=True, text=True, timeout=60)
    _ok(res, f"`{cmd}`")
    assert "bound" in res.stdout


def python_block(text, ctx, tmp_path):
    script = tmp_path / "block.py"
    script.write_text(text)
    try:
        res = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True,
                             timeout=PYTHON_BLOCK_TIMEOUT_S)
    except subprocess.TimeoutExpired as exc:
        pytest.fail(f"the python block did not finish within {PYTHON_BLOCK_TIMEOUT_S} s; last output: "
                    f"{(exc.stdout or b'')[-2000:]!r} {(exc.stderr or b'')[-2000:]!r}")
    _ok(res, "the python block")


def yaml_profile(text, ctx, tmp_path):
    name, command = _yaml_header(text)
    doc = yaml.safe_load(text)
    with open(SLURM_PROFILE) as fh:
        shipped = yaml.safe_load(fh)
    extra = set(doc) - set(shipped)
    assert not extra, f"profile block {name}: keys {sorted(extra)} are not in {SLURM_PROFILE.relative_to(REPO)}"
    for key, value in doc.items():
        if key == "default-resources":
            unknown = set(value) - set(shipped[key]) - USER_RESOURCES
            assert not unknown, f"profile block {name}: default-resources {sorted(unknown)} unknown"
            value = {k: v for k, v in value.items() if k not in USER_RESOURCES}
        assert value == shipped[key], (f"profile block {name}: {key} = {value!r}, but the shipped profile "
                                       f"has {shipped[key]!r} (the block is documented as a copy)")
    if command:  # e.g. `snakemake --workflow-profile ~/profiles/mycluster --config scene=paper`
        home = tmp_path / "home"
        profile = home / Path(name.replace("~/", "", 1)) if name.startswith("~/") else tmp_path / name
        profile.parent.mkdir(parents=True, exist_ok=True)
        profile.write_text(text)
        args = [a.replace("~", str(home), 1) if a.startswith("~/") else a for a in _args(command)]
        res = _profile_dry_run(ctx.workflow(), _placeholders(args, ctx), env={**os.environ, "HOME": str(home)})
        _ok(res, f"the dry run of `{command}` with this profile")


def yaml_scene_file(text, ctx, tmp_path):
    name, _ = _yaml_header(text)
    assert isinstance(yaml.safe_load(text), dict), f"{name} must be a mapping"
    users = [it.text for it in ITEMS if it.kind == "command" and re.search(rf"--configfile[ =]{re.escape(name)}\b",
                                                                             it.text)]
    assert users, f"scene file {name} is documented, but no documented command uses `--configfile {name}`"


def _shipped_scene_excerpt(text, ctx=None):
    """A yaml block without a file name whose top-level keys are shipped scene names."""
    if _yaml_header(text)[0] is not None:
        return False
    doc = yaml.safe_load(text)
    with open(REPO / "config" / "config.yaml") as fh:
        scenes = yaml.safe_load(fh).get("scenes", {})
    return isinstance(doc, dict) and bool(doc) and set(doc) <= set(scenes)


def yaml_shipped_excerpt(text, ctx, tmp_path):
    doc = yaml.safe_load(text)
    for name, block in doc.items():
        assert block == ctx.shipped["scenes"][name], (f"the documented scene {name!r} differs from "
                                                      f"config/config.yaml's:\n{block}\nvs\n{ctx.shipped['scenes'][name]}")


def yaml_other(text, ctx, tmp_path):
    yaml.safe_load(text)


def _is_scene_file(text):
    name, _ = _yaml_header(text)
    return name is not None and not _is_profile(name)


# (pattern on the command, handler, what it checks) - first match wins.
COMMANDS = [
    (r"^snakemake\b.*\s--report\s", snakemake_report, "report on a finished scene"),
    # any forcing flag: `--forcerun contact FILE` (rule names: every contact job) must fail here
    (r"^snakemake\b.*\s(-f|--force|-F|--forceall|-R|--forcerun)\s", snakemake_force_one,
     "forced rerun of one file on a finished scene"),
    (r"^snakemake\b.*\s--rerun-triggers\s", snakemake_rerun_edited,
     "its block after a config edit on a finished scene: only the forced case reruns"),
    (r"^snakemake\b.*\s--(unlock|lint)\b", snakemake_for_real, "run for real (cheap)"),
    (r"^snakemake\b.*\s--workflow-profile\s", snakemake_profile, "dry run with the profile"),
    (r"^snakemake(\s|$)", snakemake_dry_run, "dry run in a workflow copy"),
    (r"^make\s+[\w-]+$", make_target, "make -n TARGET"),
    (r"^python -m roughcontact\.pipeline\.runcost\s", python_runcost, "a row per rule on a finished scene"),
    (r"^python -m roughcontact\.pipeline\.progress\s", python_progress, "every solve done on a finished scene"),
    (r"^python -m roughcontact\.pipeline\.adopt\s", python_adopt, "adopts a case between two small runs"),
    (r"^python -m roughcontact\.pipeline\.config(\s|$)", python_config, "checks the config with the scene files"),
    (r"^pip install -e ", pip_extra, "the extra exists"),
    (r"^(mpiexec -n \d+|srun) python -m roughcontact\.solver\.mpi\s", mpi_command, "its arguments parse"),
    (r"^\.\s+\S+/bin/activate$", activate_venv, "the Makefile makes that venv"),
    (r"^python -c \"from roughcontact\.solver\.mpi\.slabs import write_wisdom; ", python_slab_wisdom,
     "its arguments bind to write_wisdom's and name slab problems"),
]
# (block language, predicate on the text, handler, what it checks) - first match wins.
BLOCKS = [
    ("python", lambda t: True, python_block, "runs in a subprocess"),
    ("yaml", lambda t: _is_profile(_yaml_header(t)[0]), yaml_profile, "a copy of the SLURM profile"),
    ("yaml", _is_scene_file, yaml_scene_file, "a scene file used by --configfile"),
    ("yaml", _shipped_scene_excerpt, yaml_shipped_excerpt, "equals the scene in config/config.yaml"),
    ("yaml", lambda t: _yaml_header(t)[0] is None, yaml_other, "parses"),
]
# a small run first
SLOW_HANDLERS = {snakemake_report, snakemake_force_one, snakemake_rerun_edited, python_runcost, python_progress}
SLOW_HANDLERS |= {python_block}  # the README's snippet: a 512^2 solve, ~13 s of CPU (make test-fast < 3 min)


def handler_for(item: Item):
    if item.kind == "command":
        return next((h for pat, h, _ in COMMANDS if re.search(pat, item.text)), None)
    return next((h for lang, pred, h, _ in BLOCKS if lang == item.kind and pred(item.text)), None)


def _param(item: Item):
    slow = handler_for(item) in SLOW_HANDLERS or SLOW_COMMAND.search(item.text) or (
        item.kind == "yaml" and SLOW_COMMAND.search(_yaml_header(item.text)[1]))
    return pytest.param(item, id=item.id, marks=[pytest.mark.slow] if slow else [])


# ------------------------------------------------------------------------------------- tests
def test_docs_are_parsed():
    kinds = {it.kind for it in ITEMS}
    assert {"command", "python", "yaml"} <= kinds, kinds
    texts = {it.text for it in ITEMS}
    assert "make test" in texts and ". .venv/bin/activate" in texts


def test_every_documented_item_has_a_handler():
    missing = [f"{', '.join(it.where)}: {it.kind}: {it.text.strip()[:200]}" for it in ITEMS if handler_for(it) is None]
    assert not missing, ("documented but not exercised by tests/test_docs.py (add a row to COMMANDS or "
                         "BLOCKS):\n" + "\n".join(missing))


@pytest.mark.parametrize("item", [_param(it) for it in ITEMS])
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_documented_item(item, ctx, tmp_path):
    handler = handler_for(item)
    if handler is None:
        pytest.fail(f"no handler for this {item.kind} ({', '.join(item.where)}): {item.text.strip()[:200]}")
    if item.kind == "command":
        handler(item.text, ctx)
    else:
        handler(item.text, ctx, tmp_path)


def test_the_paper_dags_size_is_given_right_wherever_it_is_given():
    """Text that gives the paper scene's job count must give the DAG's (test_workflow checks PAPER_JOBS)."""
    texts = [REPO / "Makefile", *(REPO / d for d in DOCS), *sorted((REPO / "tests").glob("*.py")),
             *sorted((REPO / "workflow").rglob("*.yaml")), *sorted((REPO / "profiles").rglob("*.yaml")),
             *sorted((REPO / "workflow").rglob("*.smk"))]
    stale = [f"{path.relative_to(REPO)}:{n}: {line.strip()}"
             for path in texts for n, line in enumerate(path.read_text().splitlines(), 1)
             for count in re.findall(r"\b(\d{3,})[- ]jobs?\b", line)
             if "paper" in line and int(count) != PAPER_JOBS]
    assert not stale, f"the paper scene plans {PAPER_JOBS} jobs, not:\n" + "\n".join(stale)


def test_bash_blocks_split_into_commands():
    assert _commands_of_bash("make run    # comment\nsnakemake --unlock && snakemake -j2 --rerun-incomplete\n") == [
        "make run", "snakemake --unlock", "snakemake -j2 --rerun-incomplete"]


def test_an_undocumented_kind_of_command_has_no_handler():
    assert handler_for(Item("command", "python -m something")) is None
    assert handler_for(Item("command", "make")) is None
    assert handler_for(Item("bash-ish", "x")) is None


# -- the code the texts name exists ---------------------------------------------------------------------------------

#: The texts a reader follows into the code (benchmarks/README.md is a dated log: its old paths are history).
NAMING_TEXTS = ("README.md", "config/README.md", "results/README.md", "tests/README.md")


def _naming_texts():
    return [REPO / name for name in NAMING_TEXTS] + sorted((REPO / "docs").rglob("*.md"))


def _resolves(dotted: str) -> bool:
    """Whether ``roughcontact.a.b...`` is a module, or an attribute chain on its longest importable prefix."""
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
            break
        except ImportError:
            continue
    else:
        return False
    for attr in parts[i:]:
        if not hasattr(obj, attr):
            return False
        obj = getattr(obj, attr)
    return True


def test_the_modules_and_names_the_texts_give_exist():
    """Every ```roughcontact.a.b``` (a module, or a module's attribute) and every ```path.py``` / ```rule.smk``` in the
    README files and docs/ names something that exists: the longest importable prefix imported, the rest looked up
    on it; a path with a folder ends a tracked file's path, a bare file name is a tracked file's name. (README's
    layout and docs/architecture.md named ``solver/elastic.py`` for a day after it had gone, results/README.md two
    functions by their modules' former names.)"""
    tracked = subprocess.run(["git", "ls-files"], cwd=REPO, capture_output=True, text=True, check=True).stdout.split()
    names = {Path(p).name for p in tracked}
    missing = []
    for path in _naming_texts():
        text = path.read_text()
        dotted = sorted(set(re.findall(r"`(roughcontact(?:\.\w+)+)(?:\(\))?`", text)))
        files = sorted(set(re.findall(r"`([\w./-]+\.(?:py|smk))`", text)))
        missing += [f"{path.relative_to(REPO)}: {name}" for name in dotted if not _resolves(name)]
        missing += [f"{path.relative_to(REPO)}: {file}" for file in files
                    if not (any(p == file or p.endswith("/" + file) for p in tracked) if "/" in file
                            else file in names)]
    assert not missing, "the texts name code that does not exist:\n" + "\n".join(missing)


def test_the_readme_layout_names_modules_that_exist():
    """Each bare name in README's layout row of a package ``src/roughcontact/<pkg>/`` is one of its modules or
    folders, a name one of its modules defines at top level, or a rule of the workflow."""
    rules = set(re.findall(r"^rule (\w+)", "".join(p.read_text() for p in (REPO / "workflow" / "rules").glob("*.smk")),
                           re.M))
    unknown, rows = [], 0
    for line in (REPO / "README.md").read_text().splitlines():
        row = re.match(r"\| `src/roughcontact/(\w+)/` \| (.*) \|$", line)
        if not row:
            continue
        rows += 1
        pkg = REPO / "src" / "roughcontact" / row.group(1)
        sources = list(pkg.rglob("*.py"))
        known = {p.stem for p in sources} | {p.name for p in pkg.rglob("*") if p.is_dir()} | rules
        for src in sources:
            known |= {a or b for a, b in re.findall(r"^(?:def|class) (\w+)|^(\w+)\s*[:=]", src.read_text(), re.M)}
        unknown += [f"{row.group(1)}: {name}" for name in re.findall(r"`([a-z_][a-z0-9_]*)/?`", row.group(2))
                    if name not in known]
    assert rows >= 8, f"README's layout table has {rows} package rows: the check no longer reads it"
    assert not unknown, "README's layout names what its package does not hold:\n" + "\n".join(unknown)
