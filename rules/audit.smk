# Audit: every study cell traceable and checkable (`snakemake audit`), and a
# seeded sample of stored solutions re-solved from their inputs
# (`snakemake audit_verify`).


rule audit:
    input:
        get_audit_inputs,
    output:
        # update(): the previous audit stays until the new one replaces it (atomically)
        csv=update("results/audit/audit.csv"),
        md=update(report("results/audit/audit.md", category="Audit")),
    log:
        "results/logs/audit/audit.log",
    group:
        "summaries"
    resources:
        mem_mb=get_mem_mb("audit"),
        runtime=get_runtime("audit"),
    params:
        studies=get_audit_studies,
        # the hardness check's pressure levels: the aggregates'
        levels=config["contact"]["pressure_levels"],
        # size, mtime and ctime of every file read: any change reruns the audit, also an
        # edit that restores the mtime (touch -r)
        stamp=get_audit_stamp,
    script:
        "../scripts/audit.py"


# audit: {strict: true} (or this target): fail the run when any cell is flagged
rule audit_strict:
    input:
        "results/audit/audit.csv",
    output:
        "results/audit/strict.ok",
    log:
        "results/logs/audit/strict.log",
    script:
        "../scripts/audit_strict.py"


rule audit_verify:
    input:
        get_audit_inputs,
    output:
        report("results/audit/verify.csv", category="Audit"),
    log:
        "results/logs/audit/verify.log",
    resources:
        mem_mb=get_mem_mb("audit_verify"),
        runtime=get_runtime("audit_verify"),
    params:
        jobs=get_audit_jobs,
        sample=config["audit"]["verify_sample"],
        seed=STUDY.audit.verify_seed,
    script:
        "../scripts/audit_verify.py"
