# Last stage: the paper's figures from papermill-parameterised notebooks.


rule figure:
    input:
        notebook=os.path.join(NOTEBOOKS, "{fig}.ipynb"),
        surfaces=get_figure_surfaces,
        aggregates=get_figure_aggregates,
    output:
        png="results/figures/{fig}.png",
        pdf="results/figures/{fig}.pdf",
        notebook="results/figures/{fig}.ipynb",
    log:
        "results/logs/figures/{fig}.log",
    benchmark:
        "results/benchmarks/rules/figures/{fig}.tsv"
    threads: 1
    resources:
        mem_mb=1000,
    params:
        parameters=get_figure_parameters,
    script:
        "../scripts/render_figure.py"
