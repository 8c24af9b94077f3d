"""The parts of eval/reproduce.py, the reproduction of the SGD-ICP paper's experiments:

  config       what is run: data, configurations, peers, figure names; log()
  runner       the sgdicp CLI runs (Runner), pairs files, CSV rows
  experiments  Table I and II (our configurations, the peers, the 7-Scenes sequence)
  figures      Fig. 1, 2 and 4 (their runs and plots)
  tables       the report's Markdown tables and number formats
  report       report.md and its sanity checks

The modules use the harness bench/peers/ (imported as `peers`), which needs the sgd_icp
package: eval/reproduce.py checks both before it imports them.
"""
import os
import sys

# bench/ on the path for `peers` (eval/reproduce.py puts it there first).
_BENCH = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                      "bench")
if _BENCH not in sys.path:
    sys.path.insert(0, _BENCH)
