#!/usr/bin/env python3
"""Cancel local "cluster" jobs: ``cancel.py JOBID [JOBID ...]``.

Called by the cluster-generic executor (Ctrl-C on Snakemake) in the
workflow's working directory. Sends SIGTERM to each job's process group
(the wrapper shell, the jobscript and the Snakemake job it runs).
"""

import os
import signal
import sys
from pathlib import Path

LOG_DIR = Path("results/logs/cluster")


def main() -> None:
    for jobid in sys.argv[1:]:
        pid_file = LOG_DIR / f"{jobid}.pid"
        if not pid_file.exists() or (LOG_DIR / f"{jobid}.exit").exists():
            continue
        try:  # submit.py started each job in a new session: its pgid is its pid
            os.killpg(int(pid_file.read_text()), signal.SIGTERM)
        except ProcessLookupError:
            pass


if __name__ == "__main__":
    main()
