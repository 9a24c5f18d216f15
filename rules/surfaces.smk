# Stage 1: seeded random rough surfaces, one HDF5 file per surface cell.


rule surfaces:
    output:
        "results/surfaces/{cell}.h5",
    log:
        "results/logs/surfaces/{cell}.log",
    benchmark:
        "results/benchmarks/rules/surfaces/{cell}.tsv"
    threads: 1
    resources:
        mem_mb=1000,
    params:
        cell=get_surface_params,
        study_seed=config["study_seed"],
    script:
        "../scripts/generate_surfaces.py"
