# Reports on the numerical model itself (not on a study cell).


rule influence_convergence:
    input:
        lambda wildcards: sorted(get_convergence_stored(wildcards).values()),
    output:
        csv="results/reports/influence_convergence.csv",
        png=report(
            "results/reports/influence_convergence.png",
            caption="../report/influence_convergence.rst",
            category="Reports",
        ),
    log:
        "results/logs/reports/influence_convergence.log",
    benchmark:
        "results/benchmarks/rules/reports/influence_convergence.tsv"
    threads: 1
    resources:
        mem_mb=get_mem_mb("influence_convergence"),
        runtime=get_runtime("influence_convergence"),
    params:
        geometry=PLAN.body.params(),
        stored=get_convergence_stored,
        settings=canonical(thawed(STUDY.reports.sections["influence_convergence"])),
        E_MPa=config["body"]["E_MPa"],
    script:
        "../scripts/influence_convergence.py"


rule speed_vs_error:
    input:
        mesh_table="results/reports/influence_convergence.csv",
        spectrum=get_speed_vs_error_spectrum_files,
    output:
        md=report(
            "results/reports/speed_vs_error.md",
            caption="../report/speed_vs_error.rst",
            category="Reports",
        ),
        csv="results/reports/speed_vs_error.csv",
        png="results/reports/speed_vs_error.png",
        counts_png="results/reports/speed_vs_error_counts.png",
        presets="results/reports/accuracy_presets.yaml",
    log:
        "results/logs/reports/speed_vs_error.log",
    benchmark:
        "results/benchmarks/rules/reports/speed_vs_error.tsv"
    threads: 1
    resources:
        mem_mb=get_mem_mb("speed_vs_error"),
        runtime=get_runtime("speed_vs_error"),
    params:
        geometry=PLAN.body.params(),
        settings=canonical(config["reports"]["speed_vs_error"]),
        E_MPa=config["body"]["E_MPa"],
        study_seed=config["study_seed"],
    script:
        "../scripts/speed_vs_error.py"


# The grid-convergence study (on demand: `snakemake grid_convergence --configfile
# config/gridconv.yaml`): the same surfaces on each grid, one contact job per grid.


rule grid_convergence_surfaces:
    output:
        "results/grid_convergence/surfaces_{gcgrid}.h5",
    log:
        "results/logs/grid_convergence/surfaces_{gcgrid}.log",
    benchmark:
        "results/benchmarks/rules/grid_convergence/surfaces_{gcgrid}.tsv"
    wildcard_constraints:
        gcgrid=r"\d+",
    threads: 1
    resources:
        mem_mb=get_mem_mb("grid_convergence"),
        runtime=get_runtime("summary"),
    params:
        settings=canonical(thawed(STUDY.reports.sections["grid_convergence"])),
        study_seed=config["study_seed"],
    script:
        "../scripts/grid_convergence_surfaces.py"


rule grid_convergence_contact:
    input:
        "results/grid_convergence/surfaces_{gcgrid}.h5",
    output:
        "results/grid_convergence/contact_{gcgrid}.h5",
    log:
        "results/logs/grid_convergence/contact_{gcgrid}.log",
    benchmark:
        "results/benchmarks/rules/grid_convergence/contact_{gcgrid}.tsv"
    wildcard_constraints:
        gcgrid=r"\d+",
    threads: 1
    resources:
        mem_mb=get_mem_mb("grid_convergence"),
        runtime=get_runtime("grid_convergence"),
    params:
        settings=canonical(thawed(STUDY.reports.sections["grid_convergence"])),
        # version of the stored layout (2: the interface quantities)
        layout=2,
    script:
        "../scripts/grid_convergence_contact.py"


rule grid_convergence:
    input:
        get_grid_convergence_contacts,
    output:
        csv="results/reports/grid_convergence.csv",
        png=report(
            "results/reports/grid_convergence.png",
            caption="../report/grid_convergence.rst",
            category="Reports",
        ),
    log:
        "results/logs/reports/grid_convergence.log",
    benchmark:
        "results/benchmarks/rules/reports/grid_convergence.tsv"
    threads: 1
    resources:
        mem_mb=500,
        runtime=get_runtime("summary"),
    script:
        "../scripts/grid_convergence.py"
