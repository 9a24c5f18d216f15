# Stage 3: contact. One job per (surface cell, geometry): every surface of the
# cell through the whole approach sweep, in non-dimensional form (sigma and E
# enter only in aggregation). Stage 4: aggregates per figure or sweep.


rule contact:
    input:
        unpack(get_contact_inputs),
    output:
        "results/contact/{job}.h5",
    log:
        "results/logs/contact/{job}.log",
    benchmark:
        "results/benchmarks/rules/contact/{job}.tsv"
    priority: CONTACT_PRIORITY
    threads: 1
    resources:
        mem_mb=get_mem_mb("contact"),
        runtime=get_runtime("contact"),
    params:
        job=get_params("contact"),
        solver=canonical(PLAN.contact.params()),
        # version of the stored layout (2: plastic area and the solutions' pressure profiles;
        # 3: the interface quantities: spots, perimeter, corrected area, gaps)
        layout=3,
    script:
        "../scripts/solve_contact.py"


rule aggregate:
    input:
        get_aggregate_inputs,
    output:
        table="results/aggregates/{study}.csv",
        moduli="results/aggregates/{study}.moduli.csv",
        meta="results/aggregates/{study}.json",
        validity="results/aggregates/{study}.validity.csv",
    log:
        "results/logs/aggregates/{study}.log",
    priority: CONTACT_PRIORITY
    group:
        "summaries"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=get_runtime("summary"),
    params:
        cells=get_aggregate_cells,
        levels=config["contact"]["pressure_levels"],
        # the probes' study-side settings by kind (the seal whose leak rate the table
        # gives, the conductance's materials; empty with every probe off)
        probes=canonical(study_probe_params(STUDY.probes)),
        # version of the stored layout (2: the sidecar holds the tables' SHA-256; 3: the
        # validity table against the hardness)
        layout=3,
    script:
        "../scripts/aggregate.py"


# The loading section: each capped cell along its loading path (load, unload, reload)
# with the cap's permanent set, on its contact job's files; aggregated per step and per
# cycle (roughcontact.study.cycle_records).
rule cycle:
    input:
        unpack(get_cycle_inputs),
    output:
        "results/cycles/{cycle}.h5",
    log:
        "results/logs/cycles/{cycle}.log",
    benchmark:
        "results/benchmarks/rules/cycles/{cycle}.tsv"
    priority: CONTACT_PRIORITY
    threads: 1
    resources:
        mem_mb=get_mem_mb("cycle"),
        runtime=get_runtime("cycle"),
    params:
        job=get_params("cycle"),
        solver=canonical(PLAN.contact.params()),
    script:
        "../scripts/solve_cycle.py"


rule aggregate_cycles:
    input:
        get_cycle_aggregate_inputs,
    output:
        table="results/aggregates/{study}.cycles.csv",
        summary="results/aggregates/{study}.cycles_summary.csv",
        meta="results/aggregates/{study}.cycles.json",
    log:
        "results/logs/aggregates/{study}.cycles.log",
    priority: CONTACT_PRIORITY
    group:
        "summaries"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=get_runtime("summary"),
    params:
        cells=get_cycle_cells,
        loading=STUDY.loading.params(),
        probes=canonical(study_probe_params(STUDY.probes)),
    script:
        "../scripts/aggregate_cycles.py"
