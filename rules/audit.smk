# Audit: every study cell traceable and checkable (`snakemake audit`), and a
# seeded sample of stored solutions re-solved from their inputs
# (`snakemake audit_verify`).


rule audit:
    input:
        get_audit_inputs,
    output:
        csv="results/audit/audit.csv",
        md=report("results/audit/audit.md", category="Audit"),
    log:
        "results/logs/audit/audit.log",
    group:
        "summaries"
    resources:
        mem_mb=get_audit_mem_mb,
        runtime=get_audit_runtime,
    params:
        studies=get_audit_studies,
    script:
        "../scripts/audit.py"


rule audit_verify:
    input:
        get_audit_inputs,
    output:
        report("results/audit/verify.csv", category="Audit"),
    log:
        "results/logs/audit/verify.log",
    resources:
        mem_mb=get_audit_verify_mem_mb,
        runtime=get_audit_verify_runtime,
    params:
        jobs=CONTACT_JOBS,
        sample=config["audit"]["verify_sample"],
        seed=config["audit"].get("verify_seed", config["study_seed"]),
    script:
        "../scripts/audit_verify.py"
