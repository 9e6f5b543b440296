"""The peak memory of a rank of the MPI solver against the ranks and its slab, and the model the ``contact`` rule asks
by (:mod:`roughcontact.solver.mpi.memory`; benchmarks/README.md, "Memory a rank").

``python benchmarks/mpi/memory.py run OUT.txt`` runs ``scaling.py`` on 256², 2048², 4096² and 8192² grids with 1 to
64 ranks (:data:`RUNS`; 2026-12-03: about 13 min on 2 cores, oversubscribed, 11 GiB at the peak), each 3 steps of at
most 4 iterations (every field is allocated in a step's first iterations, the warm start's two solutions from the
third step on), writes its output to ``OUT.txt`` and fits it; ``python benchmarks/mpi/memory.py fit OUT.txt`` reads
``scaling.py``'s lines (grid, ranks, each rank's peak RSS), fits ``a + c R + b n`` (``R`` the job's ranks, ``n`` the
nodes of a rank's slab; ``c`` from the smallest grid's runs of 8 ranks and more, where the slabs hold almost
nothing, then ``a`` and ``b`` by least squares on the runs of 2 ranks and more on the grids of 2048² and more) and
prints every run's fullest rank beside the shipped model and the ``contact`` rule's share of a rank.
"""

import datetime
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from roughcontact.pipeline.contact_jobs import contact_mpi_mem_mb
from roughcontact.solver.mpi.memory import largest_slab_nodes, rank_memory_mib

GIB, MIB = 2**30, 2**20
SCALING = Path(__file__).with_name("scaling.py")
#: The grids and, for each, the ranks of the runs.
RUNS = {256: (2, 8, 32, 64), 2048: (1, 2, 4, 8, 16, 32), 4096: (1, 2, 4, 8, 16, 32), 8192: (2, 4)}
LINE = re.compile(r"grid (\d+)x(\d+) ranks (\d+) .* peak_rss_GiB ([\d. ]+)$")


def runs(text: str) -> list[tuple[int, int, int, float]]:
    """``(nx, ny, ranks, the fullest rank's peak [GiB])`` of each of scaling.py's lines in ``text``."""
    out = []
    for line in text.splitlines():
        m = LINE.search(line.strip())
        if m:
            out.append((int(m[1]), int(m[2]), int(m[3]), max(float(v) for v in m[4].split())))
    return out


def fit(rows) -> tuple[float, float, float]:
    """``(a [MiB], c [MiB a rank of the job], b [B a node])``, as the module's docstring says."""
    small = min(r[0] for r in rows)
    tiny = [(r[2], r[3] * GIB) for r in rows if r[0] == small and r[2] >= 8]
    c = np.polyfit([t[0] for t in tiny], [t[1] for t in tiny], 1)[0]
    big = [r for r in rows if r[0] >= 2048 and r[2] >= 2]
    A = np.array([[1.0, largest_slab_nodes(r[:2], r[2])] for r in big])
    y = np.array([r[3] * GIB - c * r[2] for r in big])
    (a, b), *_ = np.linalg.lstsq(A, y, rcond=None)
    return a / MIB, c / MIB, b


def measure(out: str) -> None:
    """Every run of :data:`RUNS` (``mpiexec`` beside this Python), its lines and the machine's state in ``out``."""
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    mpiexec = str(Path(sys.executable).with_name("mpiexec"))
    state = ["sh", "-c", "uptime; nproc; free -g | head -2"]
    with open(out, "w") as fh, tempfile.TemporaryDirectory() as tmp:
        def log(text: str) -> None:
            print(text, end="", flush=True)
            fh.write(text)
            fh.flush()

        log(f"{datetime.datetime.now(datetime.UTC):%a %b %d %H:%M:%S UTC %Y}\n")
        log(subprocess.run(state, capture_output=True, text=True).stdout)
        for n, ranks in RUNS.items():
            surface = f"{tmp}/h{n}.npy"
            subprocess.run([sys.executable, str(SCALING), "--make", str(n), surface], check=True, env=env)
            for r in ranks:
                cmd = [mpiexec, "-n", str(r), sys.executable, str(SCALING), surface, "3", "--max-iter", "4"]
                log(subprocess.run(cmd, check=True, env=env, capture_output=True, text=True).stdout)
        log(f"{datetime.datetime.now(datetime.UTC):%a %b %d %H:%M:%S UTC %Y}\n")
        log(subprocess.run(["uptime"], capture_output=True, text=True).stdout)


def report(path: str) -> int:
    """The fit of ``path``'s runs and every run's fullest rank beside the model and the rule's share (markdown)."""
    rows = runs(open(path).read())
    a, c, b = fit(rows)
    print(f"fit: {a:.1f} MiB + {c:.3f} MiB a rank of the job + {b:.1f} B a node of the slab")
    print("| grid | ranks | fullest rank [MiB] | model [MiB] | measured / model | rule's share of a rank [MiB] | "
          "measured / rule |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for nx, ny, r, peak in rows:
        model = rank_memory_mib((nx, ny), r)
        share = contact_mpi_mem_mb(nx, r) / r if nx == ny else float("nan")
        print(f"| {nx}x{ny} | {r} | {peak * GIB / MIB:.0f} | {model:.0f} | {peak * GIB / MIB / model:.3f} | "
              f"{share:.0f} | {peak * GIB / MIB / share:.3f} |")
    return 0


def main(argv: list[str]) -> int:
    if len(argv) != 2 or argv[0] not in ("run", "fit"):
        print("usage: python benchmarks/mpi/memory.py run|fit OUT.txt", file=sys.stderr)
        return 2
    if argv[0] == "run":
        measure(argv[1])
    return report(argv[1])


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
