# Last stage: the paper's figures from papermill-parameterised notebooks. Each figure's
# caption in the report (report/figure.rst) is written from the study's own settings
# (params.caption: roughcontact.study.plan.captions, named by the figure registry
# roughcontact.study.plan.figures), followed by the numbers the notebook found (its
# `answers` file: reStructuredText, empty where a figure states none).


rule figure:
    input:
        notebook=os.path.join(NOTEBOOKS, "{fig}.ipynb"),
        surfaces=get_figure_surfaces,
        aggregates=get_figure_aggregates,
    output:
        png=report(
            "results/figures/{fig}.png",
            caption="../report/figure.rst",
            category="Figures",
        ),
        pdf="results/figures/{fig}.pdf",
        notebook="results/figures/{fig}.ipynb",
        answers="results/figures/{fig}.answers.rst",
    log:
        "results/logs/figures/{fig}.log",
    benchmark:
        "results/benchmarks/rules/figures/{fig}.tsv"
    group:
        "summaries"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=get_runtime("summary"),
    params:
        parameters=get_figure_parameters,
        caption=get_figure_caption,
    script:
        "../scripts/render_figure.py"


# A table (table_*) is rendered as a figure too, and its numbers are written
# as CSV beside it; the notebook gets the CSV's path as parameter `csv`.
use rule figure as table with:
    output:
        png=report(
            "results/figures/{fig}.png",
            caption="../report/figure.rst",
            category="Figures",
        ),
        pdf="results/figures/{fig}.pdf",
        notebook="results/figures/{fig}.ipynb",
        answers="results/figures/{fig}.answers.rst",
        csv="results/figures/{fig}.csv",
    wildcard_constraints:
        fig=r"table_\w+",
    params:
        parameters=lambda wildcards, output: get_figure_parameters(wildcards)
        | {"csv": output.csv},
        caption=get_figure_caption,


ruleorder: table > figure


rule config_snapshot:
    output:
        report("results/config.yaml", category="Configuration"),
    log:
        "results/logs/config_snapshot.log",
    group:
        "summaries"
    resources:
        mem_mb=500,
        runtime=get_runtime("summary"),
    params:
        config_hash=STUDY.config_hash,
    script:
        "../scripts/config_snapshot.py"
