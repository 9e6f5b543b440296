"""One large contact case over MPI ranks on a SLURM cluster, on paper, from measured per-node numbers (issue 63).

``python benchmarks/mpi/plan.py [--inputs FILE] [--set NAME=VALUE ...] [--date YYYY-MM-DD] [--out FILE]`` prints,
for each grid of ``sizes`` (N x N), the plan as markdown: nodes and ranks, memory per rank and per node, the time
of one iteration (compute-bound, memory-bandwidth-bound, the transposes), of a load step and of the whole load
schedule, and its core-hours; then the ``contact`` rule's request for the same case over ranks beside the plan. Every
number comes from the inputs file (:data:`INPUTS`, each value with what measured it or that it is assumed);
``--set`` replaces one, its value read as JSON (``--set ns_per_node_iteration=150``).

The model (benchmarks/README.md, "Paper estimate"):

- memory: ``bytes_per_node`` of a rank's slab plus ``rank_mib`` and ``per_rank_of_job_mib`` for each rank of the
  job on its node (:func:`roughcontact.solver.mpi.rank_memory_mib`, the model the ``contact`` rule asks by, which
  counts every rank of the job there); the job's first
  node also holds the job script's copy of the heights (``job_script_bytes_per_node``);
- nodes: the smallest power of two whose ranks (``node_cores`` a node) fit ``node_memory_usable`` of each node;
- compute-bound iteration: each rank's nodes at ``ns_per_node_iteration`` (one core's measured pace);
- bandwidth-bound iteration: the bytes one core moved at that pace (``core_stream_gbs``) for every node of the
  grid a machine holds, at ``node_bandwidth_gbs``: the iteration streams whole fields, so a node's cores share
  its memory bandwidth, and the slower of the two is the estimate;
- transposes: ``transposes_per_iteration`` of the half spectrum, each copied through memory
  ``transpose_copy_factor`` times and its off-node share sent at ``network_gbs``; added on top (the measured
  per-node time already holds the 2-rank run's copies: an upper bound);
- iterations per step: the largest measured step at ``iterations_measured_at_n``, times
  ``(N / iterations_measured_at_n) ** a`` for each ``a`` of ``iteration_exponents`` (low, high), rounded up.
"""

import argparse
import datetime
import json
import math
import shlex
import sys
from dataclasses import dataclass
from pathlib import Path

#: The shipped inputs: measured values with their sources, and the assumed node.
INPUTS = Path(__file__).with_name("plan_inputs.json")

GIB = 2**30
MIB = 2**20


def load_inputs(path: Path | str = INPUTS) -> dict[str, dict]:
    """The inputs of ``path``: name -> ``{"value", "unit", "source"}`` (every entry must name its source)."""
    with open(path) as fh:
        inputs = json.load(fh)["inputs"]
    lacking = [name for name, entry in inputs.items() if not entry.get("source")]
    if lacking:
        raise ValueError(f"{path}: inputs without a source: {', '.join(lacking)}")
    return inputs


def with_overrides(inputs: dict[str, dict], assignments: list[str]) -> dict[str, dict]:
    """``inputs`` with each ``NAME=VALUE`` of ``assignments`` (VALUE as JSON) replacing that input's value; its
    source says it was set on the command line."""
    out = {name: dict(entry) for name, entry in inputs.items()}
    for text in assignments:
        name, sep, value = text.partition("=")
        if not sep or name not in out:
            raise ValueError(f"--set {text!r}: expected NAME=VALUE with NAME one of {', '.join(sorted(out))}")
        out[name]["value"] = json.loads(value)
        out[name]["source"] = f"set on the command line (--set {text})"
    return out


def values(inputs: dict[str, dict]) -> dict:
    """The inputs' values by name."""
    return {name: entry["value"] for name, entry in inputs.items()}


def memory_per_rank_gib(n: int, ranks: int, p: dict) -> float:
    """Peak memory of the fullest rank [GiB]: :func:`roughcontact.solver.mpi.rank_memory_mib` (its slab's nodes at
    ``bytes_per_node``, ``rank_mib``, and ``per_rank_of_job_mib`` for each rank of the job on its node, ``node_cores``
    at most) with the inputs' values."""
    from roughcontact.solver.mpi.memory import rank_memory_mib

    return rank_memory_mib((n, n), ranks, ranks_per_machine=p["node_cores"], rank_mib=p["rank_mib"],
                           per_rank_of_job_mib=p["per_rank_of_job_mib"], bytes_per_node=p["bytes_per_node"]) * MIB / GIB


def first_node_memory_gib(n: int, nodes: int, p: dict) -> float:
    """Peak memory of the job's first node [GiB]: its ranks and the job script's copy of the heights (the fullest
    node)."""
    return p["node_cores"] * memory_per_rank_gib(n, nodes * p["node_cores"], p) + \
        p["job_script_bytes_per_node"] * n * n / GIB


def choose_nodes(n: int, p: dict) -> int:
    """The fewest nodes, a power of two (whole slabs of rows, an even split of the transposes), whose fullest node
    fits ``node_memory_usable`` of ``node_memory_gib``."""
    usable = p["node_memory_usable"] * p["node_memory_gib"]
    nodes = 1
    while first_node_memory_gib(n, nodes, p) > usable:
        nodes *= 2
        if nodes * p["node_cores"] > n:  # each rank needs at least one row of the grid
            raise ValueError(f"N = {n}: no split of at most {n} ranks fits {usable:.0f} GiB a node")
    return nodes


def compute_bound_s(n: int, ranks: int, p: dict) -> float:
    """One iteration [s] if each rank ran at the measured CPU pace: its ``n * n / ranks`` nodes at
    ``ns_per_node_iteration``."""
    return p["ns_per_node_iteration"] * 1e-9 * n * n / ranks


def bandwidth_bound_s(n: int, nodes: int, p: dict) -> float:
    """One iteration [s] if memory bandwidth limits it: the bytes a node and iteration that one core moved at the
    measured pace (``ns_per_node_iteration`` x ``core_stream_gbs``), for each node's share of the grid, at
    ``node_bandwidth_gbs``."""
    bytes_per_grid_node = p["ns_per_node_iteration"] * 1e-9 * p["core_stream_gbs"] * 1e9
    return bytes_per_grid_node * n * n / nodes / (p["node_bandwidth_gbs"] * 1e9)


def transposes_s(n: int, nodes: int, p: dict) -> float:
    """The transposes of one iteration [s]: each machine's share of the ``n (n/2 + 1)`` half spectrum copied
    through its memory and, off the node, sent over the network."""
    share = p["transpose_bytes_per_value"] * n * (n // 2 + 1) / nodes  # bytes a node holds of one transpose
    copies = p["transpose_copy_factor"] * share / (p["node_bandwidth_gbs"] * 1e9)
    network = (nodes - 1) / nodes * share / (p["network_gbs"] * 1e9)
    return p["transposes_per_iteration"] * (copies + network)


def iterations_per_step(n: int, p: dict) -> tuple[int, int]:
    """Iterations of one load step at grid ``n`` (low, high): the largest measured step scaled by
    ``(n / iterations_measured_at_n) ** a`` for each exponent, rounded up."""
    base, ratio = max(p["iterations_per_step_measured"]), n / p["iterations_measured_at_n"]
    low, high = (math.ceil(base * ratio**a) for a in p["iteration_exponents"])
    return low, high


@dataclass(frozen=True)
class Row:
    """The plan of one ``n x n`` case (times in s, memory in GiB; pairs are (low, high) iteration counts)."""

    n: int
    nodes: int
    ranks: int
    rank_gib: float
    node_gib: float
    first_node_gib: float
    compute_s: float
    bandwidth_s: float
    transposes_s: float
    iteration_s: float
    iterations: tuple[int, int]
    steps: int
    cores: int

    @property
    def step_s(self) -> tuple[float, float]:
        """One load step [s], low and high."""
        return tuple(i * self.iteration_s for i in self.iterations)

    @property
    def wall_s(self) -> tuple[float, float]:
        """The whole load schedule [s], low and high."""
        return tuple(self.steps * s for s in self.step_s)

    @property
    def core_hours(self) -> tuple[float, float]:
        """Core-hours of the schedule, whole nodes counted (a node's cores are the allocation's), low and high."""
        return tuple(w / 3600 * self.nodes * self.cores for w in self.wall_s)


def plan(n: int, p: dict, nodes: int | None = None) -> Row:
    """The plan of one ``n x n`` case.

    Parameters
    ----------
    n : int
        Grid points per side.
    p : dict
        The input values by name (:func:`values` of :func:`load_inputs`), in the units of plan_inputs.json.
    nodes : int, optional
        The node count; default the fewest that hold the case (:func:`choose_nodes`).

    Returns
    -------
    Row
        Nodes, ranks (``node_cores`` a node), memory [GiB], the iteration's three figures and its estimate [s], the
        iterations per step (low, high) and, as properties, a step's and the schedule's wall time [s] and core-hours.
    """
    nodes = choose_nodes(n, p) if nodes is None else nodes
    ranks = nodes * p["node_cores"]
    compute, bandwidth, transposes = compute_bound_s(n, ranks, p), bandwidth_bound_s(n, nodes, p), \
        transposes_s(n, nodes, p)
    rank_gib = memory_per_rank_gib(n, ranks, p)
    return Row(n=n, nodes=nodes, ranks=ranks, rank_gib=rank_gib, node_gib=p["node_cores"] * rank_gib,
               first_node_gib=first_node_memory_gib(n, nodes, p), compute_s=compute, bandwidth_s=bandwidth,
               transposes_s=transposes, iteration_s=max(compute, bandwidth) + transposes,
               iterations=iterations_per_step(n, p), steps=p["load_steps"], cores=p["node_cores"])


def _range(pair, fmt="{:.0f}") -> str:
    return f"{fmt.format(pair[0])}-{fmt.format(pair[1])}"


def plan_tables(rows: list[Row], p: dict) -> str:
    """The plan as two markdown tables: memory, then time."""
    mem = p["node_memory_gib"]
    out = ["| N | nodes (ranks) | rows per rank | memory per rank [GiB] | per node [GiB of "
           f"{mem:g}] | first node, with the job script's heights [GiB] |",
           "|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        out.append(f"| {r.n} | {r.nodes} ({r.ranks}) | {r.n / r.ranks:g} | {r.rank_gib:.2f} | {r.node_gib:.0f} | "
                   f"{r.first_node_gib:.0f} |")
    out += ["", "| N | compute-bound [s] | bandwidth-bound [s] | transposes [s] | per iteration [s] | "
                f"iterations per step | per step [min] | {p['load_steps']} steps, wall [h] | core-hours |",
            "|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        out.append(f"| {r.n} | {r.compute_s:.2f} | {r.bandwidth_s:.2f} | {r.transposes_s:.2f} | "
                   f"{r.iteration_s:.2f} | {_range(r.iterations)} | {_range([s / 60 for s in r.step_s], '{:.1f}')} | "
                   f"{_range([w / 3600 for w in r.wall_s], '{:.2f}')} | {_range(r.core_hours)} |")
    return "\n".join(out)


def inputs_table(inputs: dict[str, dict]) -> str:
    """The inputs as a markdown table: name, value and unit, source."""
    out = ["| input | value | source |", "|---|---|---|"]
    for name, entry in inputs.items():
        value = entry["value"]
        shown = ", ".join(f"{v:g}" for v in value) if isinstance(value, list) else f"{value:g}"
        out.append(f"| `{name}` | {shown} {entry['unit']} | {entry['source'].replace('|', '/')} |")
    return "\n".join(out)


def rule_request_table(rows: list[Row], request, node_memory_gib: float) -> str:
    """The ``contact`` rule's resources for each planned case over ranks beside the plan:
    ``request(n, steps, ranks)`` -> ``(mem_mb, runtime_min)`` (:func:`rule_request`). The rule's ``mem_mb`` [MiB]
    is for all ranks together; its ``mem_mb_per_cpu`` (:func:`~roughcontact.pipeline.contact_jobs.mpi_mem_mb_per_cpu`,
    one CPU a rank as under ``profiles/slurm``) is what SLURM is asked (``--mem-per-cpu``), set against the plan's
    memory per rank, with the ranks a node of ``node_memory_gib`` holds at that request (at most its cores) and
    the nodes SLURM then needs."""
    from roughcontact.pipeline.contact_jobs import mpi_mem_mb_per_cpu

    node_mib = node_memory_gib * GIB / MIB
    out = ["| N | ranks (nodes) | rule: mem_mb, all ranks | rule: `--mem-per-cpu` [MiB] | plan: a rank [MiB] | "
           f"rule / plan | ranks a {node_memory_gib:g} GiB node holds at the rule's | nodes SLURM needs | "
           "rule: runtime [min] | plan: wall [min] |",
           "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        mem_mb, runtime = request(r.n, r.steps, r.ranks)
        per_cpu = mpi_mem_mb_per_cpu(mem_mb, r.ranks)
        per_rank = r.rank_gib * GIB / MIB
        held = min(r.cores, int(node_mib // per_cpu))
        out.append(f"| {r.n} | {r.ranks} ({r.nodes}) | {mem_mb} | {per_cpu} | {per_rank:.0f} | "
                   f"{per_cpu / per_rank:.1f} | {held} | {-(-r.ranks // held) if held else 'none'} | {runtime} | "
                   f"{_range([w / 60 for w in r.wall_s])} |")
    return "\n".join(out)


def rule_request(n: int, steps: int, ranks: int) -> tuple[int, int]:
    """The ``contact`` rule's ``mem_mb`` and ``runtime`` for one case over ranks (pipeline.contact_jobs)."""
    from roughcontact.pipeline.contact_jobs import contact_mpi_mem_mb, contact_mpi_runtime_min

    return contact_mpi_mem_mb(n, ranks), contact_mpi_runtime_min(n, steps, ranks)


def report(inputs: dict[str, dict], *, date: str, command: str, request=rule_request) -> str:
    """The whole plan as markdown: how it was made, the plan's tables, the rule's request, the inputs."""
    p = values(inputs)
    rows = [plan(n, p) for n in p["sizes"]]
    return "\n\n".join([
        f"Made {date} by `{command}` (an estimate from measured per-node numbers, not a measurement):",
        plan_tables(rows, p),
        "The `contact` rule's request for the same case over ranks (`contact_mpi_mem_mb`, `contact_mpi_runtime_min`):",
        rule_request_table(rows, request, p["node_memory_gib"]),
        "Inputs (`benchmarks/mpi/plan_inputs.json`):",
        inputs_table(inputs),
    ]) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--inputs", default=str(INPUTS), help="the inputs file (default: plan_inputs.json beside this)")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                    help="replace one input's value (VALUE as JSON: 150, [50, 60]); repeatable")
    ap.add_argument("--date", default=datetime.date.today().isoformat(), help="the date the plan is dated")
    ap.add_argument("--out", help="write the markdown here as well as to stdout")
    args = ap.parse_args(argv)
    try:
        inputs = with_overrides(load_inputs(args.inputs), args.set)
    except (OSError, ValueError, KeyError) as err:
        print(f"plan.py: {err}", file=sys.stderr)
        return 2
    command = shlex.join(["python", "benchmarks/mpi/plan.py", *(sys.argv[1:] if argv is None else argv)])
    text = report(inputs, date=args.date, command=command)
    print(text, end="")
    if args.out:
        Path(args.out).write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
