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
    threads: 2
    resources:
        mem_mb=get_influence_mem_mb,
        runtime=get_influence_runtime,
    params:
        geometry=get_geometry_params,
        solver=config["body"]["solver"],
        max_memory_gb=config["body"]["max_memory_gb"],
    script:
        "../scripts/build_influence.py"
