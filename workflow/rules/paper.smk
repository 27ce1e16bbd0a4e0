# Key numbers of all studies -> results/key_numbers.json + LaTeX macros; the manuscript.


rule key_numbers:
    """Merge the studies' key-number fragments; write the JSON, the tidy CSV and the LaTeX macros."""
    input:
        KEY_NUMBER_FRAGMENTS,
    output:
        json=report("results/key_numbers.json", caption="../report/key_numbers.rst", category="numbers"),
        csv=report("results/key_numbers.csv", caption="../report/key_numbers_csv.rst", category="numbers"),
        tex="results/paper/numbers.tex",
        claims="results/paper/claims.tex",
        summary="results/paper/study_summary.tex",
        config="results/paper/config.tex",
        beside=report("results/paper/key_numbers_beside_source.html", caption="../report/key_numbers_beside.rst",
                      category="numbers"),
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
