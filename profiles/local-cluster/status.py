#!/usr/bin/env python3
"""Report the state of a local "cluster" job: running, success or failed.

Called by the cluster-generic executor as ``status.py JOBID`` in the
workflow's working directory. The exit file written when the jobscript ends
decides; without one the job runs while its process lives (a process killed
before it could write the file counts as failed).
"""

import os
import sys
from pathlib import Path

LOG_DIR = Path("results/logs/cluster")


def alive(pid: int, jobid: str) -> bool:
    """True while the job's wrapper shell runs (not a zombie, not a reused pid)."""
    proc = Path(f"/proc/{pid}")
    if proc.is_dir():
        try:
            cmdline = (proc / "cmdline").read_bytes().split(b"\0")
            state = (proc / "stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:  # it ended while we looked
            return False
        return jobid.encode() in cmdline and state != "Z"
    try:  # no /proc (macOS): signal 0 only checks that the pid exists
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def status(jobid: str) -> str:
    exit_file = LOG_DIR / f"{jobid}.exit"
    if exit_file.exists():
        return "success" if exit_file.read_text().strip() == "0" else "failed"
    pid_file = LOG_DIR / f"{jobid}.pid"
    if not pid_file.exists():
        return "failed"
    if alive(int(pid_file.read_text()), jobid):
        return "running"
    # the wrapper may have written the exit file between the two checks
    if exit_file.exists():
        return "success" if exit_file.read_text().strip() == "0" else "failed"
    return "failed"


if __name__ == "__main__":
    print(status(sys.argv[1]))
