# Stage 1: seeded random rough surfaces, one HDF5 file per surface cell; a
# measured surface (input: its file) is imported into a cell of one surface. A
# cell with a larger twin of the same statistics takes its first surfaces from
# the twin's file (input: source) instead of generating them again.


rule surfaces:
    input:
        unpack(get_surface_inputs),
    output:
        "results/surfaces/{cell}.h5",
    log:
        "results/logs/surfaces/{cell}.log",
    benchmark:
        "results/benchmarks/rules/surfaces/{cell}.tsv"
    # early, after the builds: a few seconds each, and every contact job waits on one
    priority: EARLY_PRIORITY
    group:
        "surfaces"
    threads: 1
    resources:
        mem_mb=get_mem_mb("surfaces"),
        runtime=get_runtime("surfaces"),
    params:
        cell=get_params("surfaces"),
        source=get_surface_source,
        study_seed=config["study_seed"],
        # version of the stored layout: files of an older layout are rebuilt instead of
        # refused (2: content hashes; 3: `filter` calibrated to the sample moments)
        layout=3,
    script:
        "../scripts/generate_surfaces.py"
