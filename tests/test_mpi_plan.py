"""benchmarks/mpi/plan.py (issue 63): the paper plan of a large case over MPI ranks, against a hand calculation.

One row (N = 32768 on today's inputs) is worked by hand below; every input must move the plan (scaled, the rows
change); the shipped inputs name their sources and the shipped ``cmc-32768`` scene asks for the plan's ranks.
"""
import copy
import math
import re
import shlex
from pathlib import Path

import pytest
import yaml

from conftest import REPO, load_script

plan = load_script(Path(__file__).resolve().parents[1] / "benchmarks" / "mpi" / "plan.py", "mpi_plan")

#: Today's inputs (2026-12-02), fixed here so that a re-measured plan_inputs.json leaves the hand calculation valid.
P = {"ns_per_node_iteration": 219.2, "bytes_per_node": 152, "rank_mib": 153.6, "per_rank_of_job_mib": 0.1,
     "job_script_bytes_per_node": 8,
     "iterations_per_step_measured": [53, 50, 52, 52], "iterations_measured_at_n": 8192,
     "iteration_exponents": [0.29, 0.5], "load_steps": 4, "transposes_per_iteration": 5,
     "transpose_bytes_per_value": 8, "transpose_copy_factor": 6, "node_cores": 128, "node_memory_gib": 256,
     "node_memory_usable": 0.85, "node_bandwidth_gbs": 300, "core_stream_gbs": 10, "network_gbs": 25,
     "sizes": [32768, 65536]}


def test_one_row_against_a_hand_calculation():
    r = plan.plan(32768, P)
    # memory: 152 B x 32768^2 / 128 ranks = 1.1875 GiB, + 153.6 MiB (0.15 GiB) + 0.1 MiB x 128 ranks (0.0125 GiB);
    # 128 ranks a node; + 8 B x 32768^2 = 8 GiB on the first
    assert r.rank_gib == pytest.approx(1.35)
    assert r.node_gib == pytest.approx(172.8)
    assert r.first_node_gib == pytest.approx(180.8)
    assert (r.nodes, r.ranks) == (1, 128)  # 180.8 GiB <= 0.85 x 256 = 217.6
    # compute-bound: 219.2 ns x 32768^2 / 128 = 219.2e-9 x 8388608 s
    assert r.compute_s == pytest.approx(1.838782, rel=1e-6)
    # bandwidth-bound: 219.2 ns x 10 GB/s = 2192 B a node, x 32768^2 / 300 GB/s
    assert r.bandwidth_s == pytest.approx(2192 * 1073741824 / 300e9, rel=1e-9)
    assert r.bandwidth_s == pytest.approx(7.845, abs=1e-3)
    # transposes: 5 x 6 x (8 B x 32768 x 16385) / 300 GB/s, nothing off the one node
    assert r.transposes_s == pytest.approx(5 * 6 * 8 * 32768 * 16385 / 300e9, rel=1e-9)
    assert r.transposes_s == pytest.approx(0.4295, abs=1e-4)
    assert r.iteration_s == pytest.approx(7.84545 + 0.42952, abs=1e-4)
    # iterations: 53 x 4^0.29 = 79.2 -> 80, 53 x 4^0.5 = 106
    assert r.iterations == (80, 106)
    assert r.wall_s == pytest.approx((4 * 80 * 8.27497, 4 * 106 * 8.27497), rel=1e-5)  # 2648 s, 3509 s
    assert r.core_hours == pytest.approx((2648.0 / 3600 * 128, 3508.6 / 3600 * 128), rel=1e-4)  # 94.2, 124.7


def test_a_larger_grid_takes_more_nodes_and_crosses_the_network():
    r = plan.plan(65536, P)
    # 2 nodes: 256 ranks of 2.375 + 0.15 + 0.0125 = 2.5375 GiB = 324.8 GiB a node, > 217.6; 4 nodes: 128 ranks of
    # 1.1875 + 0.15 + 0.0125 = 1.35 GiB = 172.8 GiB, + 32 GiB of heights = 204.8 (the job's ranks on other nodes
    # add nothing: per_rank_of_job_mib counts the 128 of a node)
    assert (r.nodes, r.ranks) == (4, 512) and r.first_node_gib == pytest.approx(204.8)
    share = 8 * 65536 * 32769 / 4  # bytes of one transpose a node holds; 3/4 of them leave the node
    assert r.transposes_s == pytest.approx(5 * (6 * share / 300e9 + 0.75 * share / 25e9), rel=1e-9)
    # 53 x 8^0.29 = 53 x 1.828 = 96.9, 53 x 8^0.5 = 149.9
    assert r.iterations == (math.ceil(53 * 8**0.29), math.ceil(53 * 8**0.5)) == (97, 150)


def _scaled(value, factor=0.8):
    if isinstance(value, list):
        return [_scaled(v, factor) for v in value]
    return round(value * factor) if isinstance(value, int) else value * factor


@pytest.mark.parametrize("name", sorted(P))
def test_every_input_moves_the_plan(name):
    base = [plan.plan(n, P) for n in P["sizes"]]
    changed = {**copy.deepcopy(P), name: _scaled(P[name])}
    assert [plan.plan(n, changed) for n in changed["sizes"]] != base, f"{name} changes no row of the plan"


def test_the_rule_request_is_set_beside_the_plan():
    """The rule's memory per CPU (all ranks' over the ranks, rounded up) against the plan's per rank, the ranks a
    256 GiB node holds at it (at most its 128 cores) and the nodes SLURM then needs."""
    rows = [plan.plan(n, P) for n in P["sizes"]]
    table = plan.rule_request_table(rows, lambda n, steps, ranks: (100_000 * ranks // 128, 90), 256)
    lines = table.splitlines()[2:]
    # 32768: 100000 MiB over 128 ranks = 782 MiB a CPU (781.25 up), the plan 1.35 GiB = 1382 MiB a rank; a node
    # holds its 128 cores' ranks at that: 1 node
    assert lines[0].startswith("| 32768 | 128 (1) | 100000 | 782 | 1382 | 0.6 | 128 | 1 | 90 | 44-58 |"), lines[0]
    table = plan.rule_request_table(rows, lambda n, steps, ranks: (400_000 * ranks // 128, 90), 256)
    # 3125 MiB a CPU: 262144 // 3125 = 83 ranks a node, so 128 ranks need 2 nodes and 512 need 7
    assert "| 3125 | 1382 | 2.3 | 83 | 2 |" in table.splitlines()[2] and "| 83 | 7 |" in table.splitlines()[3], table


def test_the_shipped_inputs_name_their_sources_and_the_scene_follows_the_plan():
    inputs = plan.load_inputs()
    assert set(inputs) == set(P)
    assert all(entry["source"] and "unit" in entry for entry in inputs.values())
    p = plan.values(inputs)
    scene = yaml.safe_load((REPO / "config" / "config.yaml").read_text())["scenes"]["cmc-32768"]["contact"]
    assert scene["surface"]["N"] == p["sizes"][0]
    assert scene["solver"]["ranks"] == plan.plan(scene["surface"]["N"], p).ranks
    assert scene["load"]["n_steps"] == p["load_steps"]
    # the plan's memory is the model the contact rule asks by, with its measured constants
    from roughcontact.solver.mpi import memory

    assert (p["rank_mib"], p["per_rank_of_job_mib"], p["bytes_per_node"]) == \
        (memory.RANK_MIB, memory.PER_RANK_OF_JOB_MIB, memory.BYTES_PER_NODE)


def test_the_command_line_sets_an_input_and_says_so(capsys, tmp_path):
    out = tmp_path / "plan.md"
    assert plan.main(["--set", "ns_per_node_iteration=2000", "--date", "2026-12-02", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert text == out.read_text()
    assert text.startswith("Made 2026-12-02 by `python benchmarks/mpi/plan.py --set ns_per_node_iteration=2000 ")
    assert "set on the command line (--set ns_per_node_iteration=2000)" in text
    # 2000 ns: both bounds scale with it (20 kB a node at 10 GB/s); the shipped inputs put 32768 on 1 node:
    # 2000 ns x 32768^2 / 128 ranks = 16.78 s, 20 kB x 32768^2 / 1 node / 300 GB/s = 71.58 s
    assert "| 32768 | 16.78 | 71.58 |" in text
    assert plan.main(["--set", "no_such_input=1"]) == 2
    assert "expected NAME=VALUE with NAME one of" in capsys.readouterr().err


def test_the_readme_holds_the_plan_of_the_shipped_inputs(capsys):
    """benchmarks/README.md's "Paper estimate" is the script's output, regenerated with the command it names."""
    readme = (REPO / "benchmarks" / "README.md").read_text()
    made = re.search(r"^Made \S+ by `(python benchmarks/mpi/plan\.py[^`]*)`", readme, re.M)
    assert made, "benchmarks/README.md names no plan.py command"
    assert plan.main(shlex.split(made.group(1))[2:]) == 0
    out = capsys.readouterr().out
    assert out in readme, (
        f"benchmarks/README.md's plan is not what `{made.group(1)}` prints now: regenerate it")
