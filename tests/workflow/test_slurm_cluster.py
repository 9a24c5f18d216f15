"""profiles/slurm against a real Slurm: a throw-away one-node cluster runs Fig 14 of
config/quick.yaml.

Run by ``make test-cluster``, not by ``make test`` (marker ``slurm``, deselected by
default): it needs root, and installs Debian's ``slurm-wlm`` and ``munge`` with
apt-get when their programs are missing. munged, slurmctld and slurmd run in the
foreground with their key, configuration, state and logs in a temporary
directory and on free ports; the fixture stops them by the processes it started,
after cancelling any job left, also when a test fails.

The plugin's job step removes ``SLURM_CONF``, with the ``SLURM_*`` variables
other than the job's identity, before it calls ``srun`` inside the job
(snakemake-executor-plugin-slurm-jobstep 0.6.1). On a cluster srun finds the
configuration at its default path (/etc/slurm/slurm.conf) or through slurmd
(configless); here a two-line ``srun`` first on PATH sets SLURM_CONF again, so
that nothing is written outside the test's directories.
"""

import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import pandas as pd
import pytest
from test_cluster import (
    FIG14,
    PROFILES,
    QUICK,
    REPO,
    dry_run_jobs,
    model_request,
    run_snakemake,
    wildcard_values,
)

from roughcontact.study.config import load_config
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.studies import contact_cells
from roughcontact.study.settings import Study

pytestmark = pytest.mark.slurm

PACKAGES = ["slurm-wlm", "munge"]
PROGRAMS = ["munged", "slurmctld", "slurmd", "sbatch", "srun", "squeue", "scontrol", "scancel",
            "sinfo"]
PARTITION = "compute"
# Targets go after these: --default-resources takes every word that follows it.
SLURM_ARGS = [
    "--profile", str(PROFILES / "slurm"),
    "--default-resources", "slurm_account=roughcontact", f"slurm_partition={PARTITION}",
    # The plugin waits 40 s between polls after a change; these jobs last seconds.
    "--slurm-init-seconds-before-status-checks", "5",
]
# Group submissions whose parts run one after the other (Fig 14's aggregate, then
# its figure): the largest cores and memory of a part, the sum of the run times.
# The parts of any other group run side by side: cores and memory add up.
GROUPS_IN_TURN = {"summaries"}


def install_slurm():
    """apt-get install slurm-wlm and munge, unless their programs are all found."""
    missing = [name for name in PROGRAMS if shutil.which(name) is None]
    if not missing:
        return
    if shutil.which("apt-get") is None:
        pytest.fail(f"{', '.join(missing)} not found, and no apt-get to install them")
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    start = time.monotonic()
    for cmd in (["apt-get", "update", "-qq"], ["apt-get", "install", "-y", "-qq", *PACKAGES]):
        proc = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=900)
        assert proc.returncode == 0, (proc.stdout + proc.stderr)[-3000:]
    print(f"Slurm: {' and '.join(PACKAGES)} installed in {time.monotonic() - start:.1f} s")


def free_ports(count):
    sockets = [socket.socket() for _ in range(count)]
    try:
        for s in sockets:
            s.bind(("127.0.0.1", 0))
        return [s.getsockname()[1] for s in sockets]
    finally:
        for s in sockets:
            s.close()


def slurm_conf(root, munge_socket, node_line):
    """A one-node cluster: the node as ``slurmd -C`` describes this machine, one
    partition, cores and memory as consumable resources, no accounting storage
    (sacct answers "Slurm accounting storage is disabled"). Finished jobs stay
    in slurmctld's memory for an hour (MinJobAge) for the checks."""
    node = re.match(r"NodeName=(\S+)", node_line).group(1)
    ctld_port, slurmd_port = free_ports(2)
    return node, f"""\
ClusterName=roughcontact-test
SlurmctldHost={node}(127.0.0.1)
SlurmctldPort={ctld_port}
SlurmdPort={slurmd_port}
SlurmUser=root
AuthType=auth/munge
AuthInfo=socket={munge_socket}
CredType=cred/munge
StateSaveLocation={root}/state
SlurmdSpoolDir={root}/spool
SlurmctldPidFile={root}/slurmctld.pid
SlurmdPidFile={root}/slurmd.pid
MailProg=/bin/true
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
MinJobAge=3600
ReturnToService=2
{node_line} NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName={PARTITION} Nodes={node} Default=YES MaxTime=INFINITE State=UP
"""


def wait_for(condition, timeout, what, logs=()):
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            tails = "\n".join(f"--- {log}\n{log.read_text()[-2000:]}" for log in logs)
            pytest.fail(f"{what} not within {timeout} s\n{tails}")
        time.sleep(0.5)


def stop(process):
    if process.poll() is None:
        process.terminate()
        try:
            process.wait(timeout=30)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def slurm_command(*args, timeout=30):
    proc = subprocess.run(args, capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, f"{' '.join(args)}: {proc.stderr}"
    return proc.stdout


@dataclass(frozen=True)
class Cluster:
    root: Path
    node: str


@pytest.fixture(scope="module")
def slurm(tmp_path_factory, request):
    """A running one-node Slurm; SLURM_CONF and the srun shim set for the module."""
    if os.geteuid() != 0:
        pytest.fail("the Slurm test starts slurmd, which needs root (sudo make test-cluster)")
    install_slurm()
    started = time.monotonic()
    root = tmp_path_factory.mktemp("slurm")
    # munged wants its socket in a directory that every user can enter
    socket_dir = Path(tempfile.mkdtemp(prefix="roughcontact-munge-"))
    socket_dir.chmod(0o755)
    munge_socket = socket_dir / "munge.socket"
    processes = []
    env = pytest.MonkeyPatch()

    def teardown():
        try:
            if len(processes) == 3 and processes[1].poll() is None:
                subprocess.run(["scancel", "--user", "root"], capture_output=True, timeout=30)
                deadline = time.monotonic() + 60
                while time.monotonic() < deadline and subprocess.run(
                        ["squeue", "--noheader", "--states", "PD,R,CG"], capture_output=True,
                        text=True, timeout=30).stdout.strip():
                    time.sleep(0.5)
        finally:
            for process in reversed(processes):  # slurmd, slurmctld, munged
                stop(process)
            env.undo()
            shutil.rmtree(socket_dir, ignore_errors=True)

    request.addfinalizer(teardown)

    key = root / "munge.key"
    key.write_bytes(os.urandom(1024))
    key.chmod(0o600)
    for name in ("state", "spool", "bin"):
        (root / name).mkdir()
    node_line = slurm_command("slurmd", "-C").splitlines()[0]
    node, conf = slurm_conf(root, munge_socket, node_line)
    (root / "slurm.conf").write_text(conf)
    srun = root / "bin" / "srun"
    conf_path, real_srun = root / "slurm.conf", shutil.which("srun")
    srun.write_text(f'#!/bin/sh\nSLURM_CONF={conf_path} exec {real_srun} "$@"\n')
    srun.chmod(0o755)
    for var in [var for var in os.environ if var.startswith("SLURM_")]:
        env.delenv(var)
    env.setenv("SLURM_CONF", str(root / "slurm.conf"))
    env.setenv("PATH", f"{root / 'bin'}{os.pathsep}{os.environ['PATH']}")

    def start(name, *args):
        log = root / f"{name}.log"
        with log.open("w") as out:
            processes.append(subprocess.Popen([name, *args], stdin=subprocess.DEVNULL,
                                              stdout=out, stderr=subprocess.STDOUT))
        return log

    logs = [start("munged", "--foreground", f"--key-file={key}", f"--socket={munge_socket}",
                  f"--pid-file={root / 'munged.pid'}", f"--seed-file={root / 'munged.seed'}")]
    wait_for(munge_socket.exists, 30, "munged's socket", logs)
    logs.append(start("slurmctld", "-D", "-f", str(root / "slurm.conf")))
    logs.append(start("slurmd", "-D", "-f", str(root / "slurm.conf")))

    def node_idle():
        proc = subprocess.run(["sinfo", "--noheader", "--format=%t", "--nodes", node],
                              capture_output=True, text=True, timeout=30)
        return proc.stdout.strip() == "idle"

    wait_for(node_idle, 90, f"node {node} idle", logs)
    print(f"Slurm: one-node cluster ready in {time.monotonic() - started:.1f} s")
    return Cluster(root=root, node=node)


def slurm_jobs():
    """Every job slurmctld remembers, as ``scontrol show job`` fields."""
    text = slurm_command("scontrol", "--oneliner", "show", "job")
    return [dict(re.findall(r"(\S+?)=(\S*)", line)) for line in text.splitlines() if line]


def megabytes(text):
    return int(float(text[:-1]) * {"M": 1, "G": 1024, "T": 1024**2}[text[-1]])


def minutes(text):
    """Slurm's time limit, [days-]hours:minutes:seconds, in minutes."""
    days, _, clock = text.rpartition("-")
    hours, mins, secs = (int(part) for part in clock.split(":"))
    return int(days or 0) * 1440 + hours * 60 + mins + secs / 60


def expected_submissions(dry_run_text):
    """Cores, memory (MB) and time (min) of every submission of a dry run of Fig 14 of
    the quick config, by the comment the plugin gives it: ``rule_<rule>_wildcards_<values>``
    for a job alone, ``rule_<group>`` followed by its rules for a group. Memory and time
    from the cost model (:func:`test_cluster.model_request`), the numbers a rule sets
    itself (cores; a summary's memory) from the dry run."""
    config = load_config(QUICK)
    plan = study_plan(Study.from_config(config))
    singles, groups = {}, {}
    for job in dry_run_jobs(dry_run_text):
        numbers = {name: int(job["resources"][name]) for name in ("mem_mb", "runtime")}
        numbers |= model_request(plan, config, job)  # the rule's own where the model has none
        request = (job["threads"], numbers["mem_mb"], numbers["runtime"])
        if job["group"] is None:
            values = wildcard_values(job).values()
            singles[f"rule_{job['rule']}_wildcards_{'_'.join(values)}"] = request
        else:
            groups.setdefault(job["group"], []).append(request)
    for group, parts in groups.items():
        threads, mem_mb, runtime = zip(*parts, strict=True)
        if group in GROUPS_IN_TURN:
            groups[group] = (max(threads), max(mem_mb), sum(runtime))
        else:
            groups[group] = (sum(threads), sum(mem_mb), max(runtime))
    return singles, groups


@pytest.fixture(scope="module")
def fig14_slurm(slurm, tmp_path_factory):
    workdir = tmp_path_factory.mktemp("fig14_slurm")
    dry = run_snakemake(workdir, "--dry-run", "--cores", "64", *SLURM_ARGS, FIG14)
    assert dry.returncode == 0, (dry.stdout + dry.stderr)[-4000:]
    start = time.monotonic()
    try:
        proc = run_snakemake(workdir, *SLURM_ARGS, FIG14, timeout=300)
    except subprocess.TimeoutExpired as exc:  # the jobs last seconds
        tail = (exc.stderr or b"")[-3000:]
        pytest.fail(f"Snakemake still waits after {exc.timeout} s: can it read the jobs' "
                    f"states (slurm-status-command)?\n"
                    f"{tail.decode() if isinstance(tail, bytes) else tail}")
    seconds = time.monotonic() - start
    log = proc.stdout + proc.stderr
    assert proc.returncode == 0, log[-6000:]
    return workdir, dry.stdout + dry.stderr, log, seconds


def test_every_submission_asks_slurm_for_the_rules_resources(fig14_slurm):
    _, dry_log, log, seconds = fig14_slurm
    run_id = re.search(r"SLURM run ID: (\S+)", log).group(1)
    submitted = re.findall(r"has been submitted with SLURM jobid (\d+) ", log)
    jobs = {job["JobId"]: job for job in slurm_jobs() if job["JobName"] == run_id}
    assert sorted(jobs) == sorted(submitted)  # no other submission under the run's name
    singles, groups = expected_submissions(dry_log)
    # influence and contact jobs alone, the surface cells and the summaries in groups
    assert sorted(key.split("_wildcards_")[0] for key in singles) == (
        ["rule_contact"] * 2 + ["rule_influence"] * 2)
    assert sorted(groups) == ["summaries", "surfaces"]
    assert len(jobs) == len(singles) + len(groups) == 6
    seen = []
    for job in jobs.values():
        comment = job["Comment"]
        if comment in singles:
            expected = singles[comment]
        else:
            (group,) = [g for g in groups if comment.startswith(f"rule_{g}_")]
            expected, comment = groups[group], group
        seen.append(comment)
        threads, mem_mb, runtime = expected
        assert (job["JobState"], job["ExitCode"]) == ("COMPLETED", "0:0"), job
        assert job["Partition"] == PARTITION
        assert int(job["CPUs/Task"]) == threads, (comment, job["CPUs/Task"], expected)
        assert megabytes(job["MinMemoryNode"]) == mem_mb, (comment, job["MinMemoryNode"])
        assert minutes(job["TimeLimit"]) == runtime, (comment, job["TimeLimit"])
    assert sorted(seen) == sorted([*singles, *groups])  # each submitted once
    # more than one core somewhere (the surface cells side by side): CPUs/Task is what
    # was asked for, not Slurm's default of one
    assert max(threads for threads, _, _ in [*singles.values(), *groups.values()]) > 1
    print(f"Slurm: {len(jobs)} submissions in {seconds:.1f} s")


def test_slurm_results_equal_a_plain_run(fig14_slurm, tmp_path):
    workdir = fig14_slurm[0]
    plain = run_snakemake(tmp_path, "--cores", "2", FIG14)
    assert plain.returncode == 0, plain.stderr[-4000:]
    for name in ("fig14.csv", "fig14.moduli.csv"):
        ours = pd.read_csv(workdir / "results" / "aggregates" / name)
        theirs = pd.read_csv(tmp_path / "results" / "aggregates" / name)
        assert len(ours) > 0
        pd.testing.assert_frame_equal(ours, theirs, check_exact=True)
    png = (workdir / FIG14).read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 1000


def test_a_job_slurm_ends_without_success_stops_the_run(slurm, tmp_path):
    """squeue still lists a finished job (MinJobAge): the plugin reads a cancelled
    job's state and the run stops with it, instead of waiting. (An influence build,
    submitted alone: Snakemake reports a failed group without the plugin's message.)"""
    geometry = contact_cells(Study.from_config(load_config(QUICK)), "fig14")[0].geometry.key
    target = f"results/influence/{geometry}.h5"
    node = f"NodeName={slurm.node}"
    slurm_command("scontrol", "update", node, "State=DRAIN", "Reason=roughcontact-test")
    cmd = [sys.executable, "-m", "snakemake", "--snakefile", str(REPO / "Snakefile"),
           "--directory", str(tmp_path), "--configfile", str(QUICK), "--retries", "0",
           *SLURM_ARGS, target]
    log = tmp_path / "snakemake.log"
    start = time.monotonic()
    try:
        with log.open("w") as out:
            process = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT, cwd=tmp_path)
        try:  # the job waits on the drained node until it is cancelled
            while process.poll() is None and time.monotonic() - start < 180:
                subprocess.run(["scancel", "--user", "root", "--state", "PENDING"],
                               capture_output=True, timeout=30)
                time.sleep(1)
        finally:
            stop(process)
    finally:
        slurm_command("scontrol", "update", node, "State=RESUME")
    seconds = time.monotonic() - start
    text = log.read_text()
    assert process.returncode not in (0, None) and seconds < 180, text[-4000:]
    assert "SLURM status is: 'CANCELLED'" in text, text[-4000:]
    assert not (tmp_path / target).exists()
    print(f"Slurm: a cancelled job stopped the run in {seconds:.1f} s")
