"""Shared fixtures: paths of the repository and a runner for the snakemake CLI."""
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
SNAKEMAKE = str(Path(sys.executable).parent / "snakemake")


@pytest.fixture(scope="session")
def repo():
    return REPO


@pytest.fixture(scope="session")
def shipped_config():
    with open(REPO / "config" / "config.yaml") as fh:
        return yaml.safe_load(fh)


def run_snakemake(workdir, *args, timeout=900):
    """Run snakemake in ``workdir`` (a copy of the workflow); returns CompletedProcess."""
    return subprocess.run(
        [SNAKEMAKE, *args], cwd=workdir, capture_output=True, text=True, timeout=timeout
    )


def copy_workflow(dest: Path, config: dict | None = None) -> Path:
    """Copy Snakefile, workflow/, config/ and envs/ into ``dest``; optionally replace the config."""
    dest.mkdir(parents=True, exist_ok=True)
    shutil.copy(REPO / "Snakefile", dest / "Snakefile")
    shutil.copytree(REPO / "workflow", dest / "workflow", dirs_exist_ok=True)
    shutil.copytree(REPO / "config", dest / "config", dirs_exist_ok=True)
    shutil.copytree(REPO / "envs", dest / "envs", dirs_exist_ok=True)
    if config is not None:
        with open(dest / "config" / "config.yaml", "w") as fh:
            yaml.safe_dump(config, fh, sort_keys=False)
    return dest
