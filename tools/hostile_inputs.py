#!/usr/bin/env python3
"""Runs the hostile corpus of scenario, study and tool inputs and tallies what became of them.

Every hand-written input (scenarios, study files, the tools' inputs and arguments) is
invalid; each generated one (seeded: the same inputs every run) puts a hostile value into a
numeric field of a shipped scenario or edits a shipped file's text, and may happen to be valid.
A refusal counts when it is the one line `FILE_OR_--override[:LINE]: FIELD: MESSAGE` within
2 s of CPU time (a tool's: one `error: ` line, exit status 2); anything else (another
exception, a hang, a missing line, a slow refusal) is a defect, listed after the table.
Exit status 1 when there is one (`lab/hostile_inputs.py`).

    python tools/hostile_inputs.py [--examples 200] [--seed 1]
"""

import argparse
import sys
import tempfile
from pathlib import Path

try:  # without the [study] extra: one line naming it, not a traceback
    from tqdm import tqdm
except ImportError:
    from corobot_drake.extras import exit_without

    exit_without("tools/hostile_inputs.py", "study")

from corobot_drake.simulation import quiet_drake_warnings
from lab import hostile_inputs as hi


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--examples", type=int, default=200,
                   help="generated inputs of each kind")
    p.add_argument("--seed", type=int, default=1, help="seed of the generated inputs")
    args = p.parse_args(argv)
    quiet_drake_warnings()
    with tempfile.TemporaryDirectory(prefix="corobot-hostile-") as tmp, tqdm(
            total=len(hi.HAND_WRITTEN) + len(hi.STUDIES) + len(hi.TOOLS) + 2 * args.examples,
            unit="input",
            file=sys.stderr) as bar:
        tallies = [hi.run_hand_written(Path(tmp), bar.update),
                   *hi.run_studies_and_tools(Path(tmp), bar.update),
                   *hi.run_generated(Path(tmp), args.examples, args.seed, bar.update)]
    print(hi.table(tallies))
    defects = [d for t in tallies for d in t.defects]
    for defect in defects:
        print(f"defect: {defect}")
    return 1 if defects else 0


if __name__ == "__main__":
    sys.exit(main())
