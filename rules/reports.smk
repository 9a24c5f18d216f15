# Reports on the numerical model itself (not on a study cell).


rule influence_convergence:
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
    threads: 2
    resources:
        mem_mb=get_convergence_mem_mb,
    params:
        geometry=get_body_geometry,
        settings=canonical(config.get("reports", {}).get("influence_convergence", {})),
        E_MPa=config["body"]["E_MPa"],
    script:
        "../scripts/influence_convergence.py"
