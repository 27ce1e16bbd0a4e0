#!/usr/bin/env bash
# docs/workflow/<study>.md: each study's rule graph as drawn by Snakemake (--rulegraph mermaid-js),
# rendered by any Mermaid viewer (GitHub, GitLab, VS Code). Run by `make dag`.
set -euo pipefail
cd "$(dirname "$0")/../.."
SNAKEMAKE=${SNAKEMAKE:-.venv/bin/snakemake}
for study in fusion nr tunnel handover chain fidelity; do
  {
    echo "# The \`$study\` target's rules"
    echo
    echo "Drawn by \`snakemake --rulegraph mermaid-js $study\` (\`make dag\`): each box a rule, each arrow"
    echo "an input it reads; the sharded rules run as many jobs as there are points, shards or batches."
    echo "The rules themselves: \`workflow/rules/\`; the study's model: \`docs/model/\`."
    echo
    echo '```mermaid'
    "$SNAKEMAKE" --rulegraph mermaid-js "$study" --workflow-profile workflow/profiles/default 2>/dev/null
    echo '```'
  } > "docs/workflow/$study.md"
done
