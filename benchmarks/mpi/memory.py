"""The peak memory of a rank of the MPI solver against the ranks and its slab, and the model the ``contact`` rule asks
by (:mod:`roughcontact.solver.mpi.memory`; benchmarks/README.md, "Memory a rank").

``python benchmarks/mpi/memory.py run OUT.txt`` runs ``scaling.py`` on 256², 2048², 4096² and 8192² grids with 1 to
64 ranks (:data:`RUNS`; 2026-12-04: about 7 min on 2 cores, oversubscribed, 11 GiB at the peak), each 3 steps of at
most 4 iterations (every field is allocated in a step's first iterations, the warm start's two solutions from the
third step on), writes its output to ``OUT.txt`` and fits it; ``python benchmarks/mpi/memory.py fit OUT.txt`` reads
``scaling.py``'s lines (grid, ranks, each rank's peak RSS and the other ranks' shared-memory pages it mapped: what it
held of its own is the difference), fits ``a + c R + b n`` to the fullest rank's (``R`` the job's ranks, ``n`` the
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
from roughcontact.solver.mpi.slabs import split

GIB, MIB = 2**30, 2**20
SCALING = Path(__file__).with_name("scaling.py")
#: The grids and, for each, the ranks of the runs.
RUNS = {256: (2, 8, 32, 64), 2048: (1, 2, 4, 8, 16, 32), 4096: (1, 2, 4, 8, 16, 32), 8192: (2, 4)}
LINE = re.compile(r"grid (\d+)x(\d+) ranks (\d+) .* peak_rss_GiB ([\d. ]+?)(?: peer_window_GiB ([\d. ]+))?$")


def runs(text: str) -> list[tuple[int, int, int, float, float]]:
    """``(nx, ny, ranks, held, rss)`` of each of scaling.py's lines in ``text``: ``held`` the most a rank held of its
    own [GiB] (its peak RSS less the other ranks' shared-memory pages it mapped, where the line counts them), ``rss``
    the largest peak RSS [GiB]."""
    out = []
    for line in text.splitlines():
        m = LINE.search(line.strip())
        if m:
            rss = [float(v) for v in m[4].split()]
            peer = [float(v) for v in m[5].split()] if m[5] else [0.0] * len(rss)
            out.append((int(m[1]), int(m[2]), int(m[3]), max(r - p for r, p in zip(rss, peer, strict=True)),
                        max(rss)))
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


def peer_pages(shape, ranks: int, per_machine: int | None = None, page: int = 4096) -> list[int]:
    """Bytes of the other ranks' window parts each rank maps, by the layout alone [one value a rank]: the pages it
    writes its transposed blocks into (``FftwSlabFFT._transpose``: a forward's rows of each other rank's columns,
    ``(cols_r, nx)``, a backward's columns of each other rank's rows, ``(rows_r, ny // 2 + 1)``), in both
    precisions, each part page-aligned with its ``col_spec`` from the next page on; the ranks on a machine are
    ``per_machine`` consecutive ones (default: all on one)."""
    nx, ny = int(shape[0]), int(shape[1])
    nc = ny // 2 + 1
    rows, cols = split(nx, ranks), split(nc, ranks)
    block = int(per_machine or ranks)
    out = []
    for me in range(ranks):
        (x0, x1), (c0, c1) = rows[me], cols[me]
        total = 0
        for r in range(me // block * block, min(ranks, (me // block + 1) * block)):
            if r == me:
                continue
            nrow, ncol = rows[r][1] - rows[r][0], cols[r][1] - cols[r][0]
            for item in (8, 16):
                at = -(-nrow * nc * item // page) * page  # col_spec's offset in the part
                for base, n, width, lo, hi in ((at, ncol, nx, x0, x1), (0, nrow, nc, c0, c1)):
                    start = base + (np.arange(n) * width + lo) * item
                    first, last = start // page, (start + (hi - lo) * item - 1) // page
                    touched = np.zeros(int(last.max()) + 2, dtype=np.int64)
                    np.add.at(touched, first, 1)
                    np.add.at(touched, last + 1, -1)
                    total += int(np.count_nonzero(np.cumsum(touched))) * page
        out.append(total)
    return out


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
    """The fit of ``path``'s runs and every run's fullest rank beside the model and the rule's share (markdown): what
    it held of its own, and its peak RSS with the other ranks' shared pages it mapped."""
    rows = runs(open(path).read())
    a, c, b = fit(rows)
    print(f"fit: {a:.1f} MiB + {c:.3f} MiB a rank of the job + {b:.1f} B a node of the slab")
    print("| grid | ranks | held [MiB] | model [MiB] | held / model | rule's share of a rank [MiB] | held / rule | "
          "peak RSS [MiB] | RSS / rule |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for nx, ny, r, held, rss in rows:
        model = rank_memory_mib((nx, ny), r)
        share = contact_mpi_mem_mb(nx, r) / r if nx == ny else float("nan")
        held, rss = held * GIB / MIB, rss * GIB / MIB
        print(f"| {nx}x{ny} | {r} | {held:.0f} | {model:.0f} | {held / model:.3f} | {share:.0f} | {held / share:.3f} | "
              f"{rss:.0f} | {rss / share:.3f} |")
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
