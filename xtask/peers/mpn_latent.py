"""Runs the PyTorch MPN peer (`shared/peers/bench_mpn.py`) at another latent width.

usage: mpn_latent.py SCRIPT LATENT [ARGS...]

The peer fixes its width in the module constant LATENT (64, the Poisson network); Console's
network is 128 wide. This imports SCRIPT as a module, sets LATENT, and runs its `main()` with
ARGS. The peer runs each case in a child process of the unmodified script, which would be 64
wide again, so the cases run in this process instead: the peak RSS a case reports is then the
largest so far, not its own.
"""

import importlib.util
import os
import sys

if len(sys.argv) < 3:
    sys.exit(__doc__)
script, latent = sys.argv[1], int(sys.argv[2])
sys.path.insert(0, os.path.dirname(os.path.abspath(script)))
spec = importlib.util.spec_from_file_location("bench_mpn", script)
peer = importlib.util.module_from_spec(spec)
spec.loader.exec_module(peer)
peer.LATENT = latent


def run_in_process(variant, n, mode, n_steps, self_loops, peaks):
    result = peer.bench(variant, n, mode, n_steps, self_loops)
    result["latent"] = latent
    peer.log(f"  {variant:10s} N={n:>7d} D={latent} {mode:5s}: {result['nodes_per_s']:>9.0f} nodes/s")
    return result


peer.run_isolated = run_in_process
sys.argv = [script] + sys.argv[3:]
peer.main()
