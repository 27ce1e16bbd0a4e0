# Key numbers of all studies -> results/key_numbers.json + LaTeX macros; the manuscript.


rule key_numbers:
    """Merge the studies' key-number fragments; write the JSON, the tidy CSV, its filterable
    HTML table and the LaTeX macros."""
    input:
        KEY_NUMBER_FRAGMENTS,
    output:
        json=report("results/key_numbers.json", caption="../report/key_numbers.rst", category="numbers"),
        csv=report("results/key_numbers.csv", caption="../report/key_numbers_csv.rst", category="numbers"),
        table=report(
            "results/paper/key_numbers_table.html", caption="../report/key_numbers_table.rst", category="numbers"
        ),
        tex="results/paper/numbers.tex",
        claims="results/paper/claims.tex",
        summary="results/paper/study_summary.tex",
        config="results/paper/config.tex",
        beside=report(
            "results/paper/key_numbers_beside_source.html",
            caption="../report/key_numbers_beside.rst",
            category="numbers",
        ),
    params:
        config=config,
    log:
        "results/logs/paper/key_numbers.log",
    benchmark:
        "results/benchmarks/paper/key_numbers.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/paper/numbers.py"


rule nr_map_dataset:
    """The reproduction map's key numbers as a dataset (cell x receiver x claim, each claim's
    metric with its interval; railradio.nr.study.map_dataset), from the map's fragment: its
    published record while current, else the map's run (nr_map.smk)."""
    input:
        nr_records.MAP.fragment(REPO_ROOT, config, "results/nr/map/key_numbers.json"),
    output:
        "results/nr/map/reproduction_map.nc",
    params:
        cells=plain(NR_PLAN.map_cells),
        nr=NR,
    log:
        "results/logs/nr/map/dataset.log",
    benchmark:
        "results/benchmarks/nr/map/dataset.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_map/dataset.py"


rule paper:
    """Build results/paper/main.pdf from paper/main.tex (needs latexmk; see README)."""
    input:
        tex="paper/main.tex",
        numbers="results/paper/numbers.tex",
        claims="results/paper/claims.tex",
        summary="results/paper/study_summary.tex",
        config="results/paper/config.tex",
        figures=[f for f in FIGURES if f.endswith(".pdf")],
    output:
        "results/paper/main.pdf",
    log:
        "results/logs/paper/latexmk.log",
    benchmark:
        "results/benchmarks/paper/latexmk.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/paper/build.py"
