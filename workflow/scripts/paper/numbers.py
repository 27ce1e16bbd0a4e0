"""Adapter: key-number fragments -> results/key_numbers.json, results/key_numbers.csv (tidy,
with verdicts: railradio.keytable) and its filterable HTML table (railradio.keyhtml), numbers.tex, claims.tex, the per-study summary of the appendix, and the report's table of our key
numbers beside the source papers'."""
import json

from railradio.io import write_json, write_text
from railradio.keyhtml import filterable_table
from railradio.keynumbers import claims_html, claims_table, config_to_latex, merge, to_latex
from railradio.keytable import study_summary_latex, to_csv
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
setup_script(smk.log[0])
fragments = []
for path in smk.input:
    with open(path, encoding="utf-8") as fh:
        fragments.append(json.load(fh))
numbers = merge(fragments)
write_json(smk.output.json, numbers)
write_text(smk.output.csv, to_csv(numbers))
write_text(smk.output.table, filterable_table(numbers))
write_text(smk.output.tex, to_latex(numbers))
write_text(smk.output.claims, claims_table(numbers, with_source_only=True))
# the appendix: per study, how many keys and how many source claims are met (every key is in
# results/key_numbers.csv and docs/keys.md, not in a 3 000-row table)
write_text(smk.output.summary, study_summary_latex(numbers))
write_text(smk.output.config, config_to_latex(smk.params.config))
write_text(smk.output.beside, claims_html(numbers))
