# railradio — the study pipeline.  Thin: config, validation, rule files, targets.
# Run with `make figures` or `snakemake -j2 --workflow-profile workflow/profiles/default figures`.
from snakemake.utils import min_version

min_version("9.0")


configfile: "config/config.yaml"


include: "workflow/rules/common.smk"
include: "workflow/rules/fusion.smk"
include: "workflow/rules/nr.smk"
include: "workflow/rules/nr_imm.smk"
include: "workflow/rules/nr_map.smk"
include: "workflow/rules/nr_fidelity.smk"
include: "workflow/rules/handover.smk"
include: "workflow/rules/chain.smk"
include: "workflow/rules/tunnel.smk"
include: "workflow/rules/paper.smk"


set_code_hashes(workflow.rules)


rule all:
    default_target: True
    input:
        FIGURES,
        "results/key_numbers.json",
        "results/paper/numbers.tex",


rule figures:
    input:
        FIGURES,


rule numbers:
    input:
        "results/key_numbers.json",
        "results/paper/numbers.tex",


rule fusion:
    input:
        STUDY_FIGURES["fusion"],
        "results/fusion/key_numbers.json",
        "results/sens/fusion/key_numbers.json",


rule nr:
    input:
        STUDY_FIGURES["nr"],
        "results/nr/key_numbers.json",


rule fidelity:
    input:
        "results/nr/fidelity/key_numbers.json",


# the nr targets published as records (make records; railradio.nr.records)
rule records:
    input:
        "results/nr/map/key_numbers.json",
        "results/nr/cases/key_numbers.json",
        STUDY_FIGURES["nr_map"],
        STUDY_FIGURES.get("nr_sensitivity", []),


rule nr_imm_all:
    input:
        STUDY_FIGURES["nr_imm"],
        "results/nr/imm/key_numbers.json",


rule handover:
    input:
        STUDY_FIGURES["handover"],
        STUDY_FIGURES["handover_correction"],
        "results/handover/key_numbers.json",


rule chain:
    input:
        STUDY_FIGURES["chain"],
        "results/chain/key_numbers.json",


rule tunnel:
    input:
        STUDY_FIGURES["tunnel"],
        "results/tunnel/key_numbers.json",
