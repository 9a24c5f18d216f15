# Stage 2: influence coefficients of the finite block, once per geometry.
# E does not enter (the file holds E * C); a geometry whose estimated peak
# memory exceeds body.max_memory_gb is refused before it is built.


rule influence:
    output:
        "results/influence/{geometry}.h5",
    log:
        "results/logs/influence/{geometry}.log",
    benchmark:
        "results/benchmarks/rules/influence/{geometry}.tsv"
    # first, the longest first: a build needs no input, and the finest one is the
    # longest job of a study (60 x 60 converged: 75 s), on which the longest contact
    # jobs wait
    priority: get_influence_priority
    # one: the sparse factorization is the only multithreaded part of a build (about
    # 40 % of it), and a second reserved core would idle through the rest
    threads: 1
    resources:
        mem_mb=get_mem_mb("influence"),
        runtime=get_runtime("influence"),
    params:
        geometry=get_params("influence"),
        solver=config["body"]["solver"],
        max_memory_gb=config["body"]["max_memory_gb"],
    script:
        "../scripts/build_influence.py"


# operator: auto: the half-space where its errors, measured on the planned model
# (dense or hybrid, built above under its own name), meet body.halfspace_tolerance,
# else that model. The choice decides which contact jobs run (a checkpoint), so a
# geometry that resolves to the model it had keeps its files.
checkpoint influence_choice:
    input:
        lambda wildcards: layout.influence(planned_choice(wildcards).key),
    output:
        "results/influence/choices/{auto}.json",
    log:
        "results/logs/influence/choices/{auto}.log",
    benchmark:
        "results/benchmarks/rules/influence_choice/{auto}.tsv"
    threads: 1
    resources:
        mem_mb=get_mem_mb("choice"),
        runtime=get_runtime("choice"),
    params:
        geometry=get_params("choice"),
        planned=lambda wildcards: planned_choice(wildcards).params(),
    script:
        "../scripts/choose_influence.py"


# Two bodies (Eq 17-18) on a dense first body: the two influence models summed once per
# pair (and modulus ratio), shared by every contact job on it; a counter body below
# counterface.rigid_share of the compliance is treated as rigid (no matrix written).
rule pair_influence:
    input:
        first=lambda wildcards: layout.influence(PLAN.pairs[wildcards.pair].first.key),
        second=lambda wildcards: layout.influence(PLAN.pairs[wildcards.pair].second.key),
    output:
        "results/influence/pairs/{pair}.h5",
    log:
        "results/logs/influence/pairs/{pair}.log",
    benchmark:
        "results/benchmarks/rules/pair_influence/{pair}.tsv"
    priority: EARLY_PRIORITY
    threads: 1
    resources:
        mem_mb=get_mem_mb("pair"),
        runtime=get_runtime("pair"),
    params:
        pair=get_params("pair"),
    script:
        "../scripts/build_pair.py"


# The thermal influence k R of a block whose conductance the contact jobs record
# (conductance.body: block): built once per block (size, thickness, grid, mesh; E, nu
# and the base do not enter), read by every contact job on it.
rule thermal_influence:
    output:
        "results/influence/thermal/{thermal}.h5",
    log:
        "results/logs/influence/thermal/{thermal}.log",
    benchmark:
        "results/benchmarks/rules/thermal_influence/{thermal}.tsv"
    priority: EARLY_PRIORITY
    threads: 1
    resources:
        mem_mb=get_mem_mb("thermal"),
        runtime=get_runtime("thermal"),
    params:
        thermal=get_params("thermal"),
        solver=config["body"]["solver"],
    script:
        "../scripts/build_thermal.py"
