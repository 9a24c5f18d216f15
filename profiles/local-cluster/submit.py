#!/usr/bin/env python3
"""Submit a Snakemake jobscript to the local "cluster": run it in the background.

Called by the cluster-generic executor as ``submit.py JOBSCRIPT`` in the
workflow's working directory. Starts the jobscript detached from Snakemake
(its own session, output to ``results/logs/cluster/<jobid>.log``), records
the submission in ``results/logs/cluster/submissions.tsv`` and prints the job
id. A wrapper shell writes the jobscript's exit code to ``<jobid>.exit`` when
it ends; ``status.py`` reads it.
"""

import json
import shlex
import subprocess
import sys
import time
import uuid
from pathlib import Path

LOG_DIR = Path("results/logs/cluster")


def job_properties(jobscript: Path) -> dict:
    """The ``# properties = {...}`` line Snakemake writes into every jobscript."""
    for line in jobscript.read_text().splitlines():
        if line.startswith("# properties = "):
            return json.loads(line.removeprefix("# properties = "))
    return {}


def main() -> None:
    jobscript = Path(sys.argv[-1]).resolve()
    LOG_DIR.mkdir(parents=True, exist_ok=True)
    jobid = f"local-{uuid.uuid4().hex[:12]}"
    log = LOG_DIR / f"{jobid}.log"
    exit_file = LOG_DIR / f"{jobid}.exit"
    # the exit code is written under a temporary name and renamed, so the
    # status script never reads a half-written file
    wrapper = (
        f"/bin/sh {shlex.quote(str(jobscript))} > {shlex.quote(str(log))} 2>&1; "
        f"echo $? > {shlex.quote(str(exit_file))}.tmp; "
        f"mv {shlex.quote(str(exit_file))}.tmp {shlex.quote(str(exit_file))}"
    )
    # the job id as the shell's $0: status.py finds the process by it
    process = subprocess.Popen(
        ["/bin/sh", "-c", wrapper, jobid],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    (LOG_DIR / f"{jobid}.pid").write_text(f"{process.pid}\n")
    props = job_properties(jobscript)
    name = props.get("rule") or props.get("groupid", "")
    resources = props.get("resources", {})
    row = [
        time.strftime("%Y-%m-%dT%H:%M:%S"),
        jobid,
        props.get("type", ""),
        name,
        str(props.get("threads", "")),
        str(resources.get("mem_mb", "")),
        str(resources.get("runtime", "")),
        ",".join(props.get("output") or []),
    ]
    submissions = LOG_DIR / "submissions.tsv"
    with submissions.open("a") as f:
        if f.tell() == 0:
            f.write("time\tjobid\ttype\tname\tthreads\tmem_mb\truntime\toutput\n")
        f.write("\t".join(row) + "\n")
    print(jobid)


if __name__ == "__main__":
    main()
