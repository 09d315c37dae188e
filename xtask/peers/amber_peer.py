"""What the peer benchmarks share: the case `cargo xtask bench` wrote, timing, the result file.

`cargo xtask bench NAME --peer-python PY` runs `PY xtask/peers/bench_NAME.py DIR`. DIR holds
`input.json` (the settings of the case) and `.npy` arrays (the mesh, points or field our bench
works on); the script times the peer library on exactly that input and writes `DIR/result.json`.
The thread counts come from the environment xtask sets (OMP_NUM_THREADS and the like, and
PEERS_THREADS), which numpy, scipy and OpenMP read when they load.
"""

import json
import os
import platform
import statistics
import sys
import time
from importlib import metadata

THREADS = int(os.environ.get("PEERS_THREADS", "1"))


class Case:
    """The directory xtask wrote: its settings (`input`), its arrays, and where results go."""

    def __init__(self):
        if len(sys.argv) != 2:
            sys.exit(f"usage: {sys.argv[0]} DIR  (a directory written by `cargo xtask bench`)")
        self.dir = sys.argv[1]
        with open(os.path.join(self.dir, "input.json")) as f:
            self.input = json.load(f)

    def array(self, name):
        import numpy

        return numpy.load(os.path.join(self.dir, f"{name}.npy"))

    def save(self, name, array):
        """Writes an array for xtask to read back: float64 or uint32 only (what its reader takes)."""
        import numpy

        assert array.dtype in (numpy.float64, numpy.uint32), array.dtype
        numpy.save(os.path.join(self.dir, f"{name}.npy"), numpy.ascontiguousarray(array))

    def finish(self, result, packages):
        """Writes `result.json`: `result` with the packages' versions, the threads and Python."""
        result = {
            "versions": {name: metadata.version(name) for name in packages},
            "threads": THREADS,
            "python": platform.python_version(),
            **result,
        }
        with open(os.path.join(self.dir, "result.json"), "w") as f:
            json.dump(result, f, indent=1)


def timed(work, repeats, warmup=0):
    """Runs `work()` `warmup` times untimed, then `repeats` times (at least once).

    Returns the median wall seconds, every run's wall seconds, the median CPU seconds of this
    process (all threads) and the last run's result.
    """
    for _ in range(warmup):
        work()
    wall, cpu, result = [], [], None
    for _ in range(max(repeats, 1)):
        start, start_cpu = time.perf_counter(), time.process_time()
        result = work()
        wall.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return statistics.median(wall), wall, statistics.median(cpu), result


def log(message):
    """A progress line, flushed (xtask passes the script's output through)."""
    print(f"  [peer] {message}", flush=True)
