"""Adapter: compile the manuscript with latexmk in results/paper/ and reject a PDF with
undefined references, citations or key numbers."""
import re
import shutil
import subprocess
from pathlib import Path

from railradio.io import atomic_path
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
log = setup_script(smk.log[0])
if shutil.which("latexmk") is None:
    raise SystemExit("latexmk is not installed: apt-get install latexmk texlive-latex-recommended "
                     "texlive-latex-extra texlive-fonts-recommended (see README)")
out = Path(smk.output[0])
build = out.parent
shutil.copyfile(smk.input.tex, build / "main.tex")
run = subprocess.run(
    ["latexmk", "-pdf", "-interaction=nonstopmode", "-halt-on-error", "-file-line-error", "main.tex"],
    cwd=build, capture_output=True, text=True, check=False,
)
log.info("%s", run.stdout[-20000:])
texlog = (build / "main.log").read_text(encoding="utf-8", errors="replace")
bad = re.findall(r"^.*(?:undefined|Undefined control sequence|There were undefined).*$", texlog, re.M)
if run.returncode != 0 or bad:
    out.unlink(missing_ok=True)
    raise SystemExit("LaTeX failed or left undefined references:\n" + "\n".join(bad[:20]))
with atomic_path(out) as tmp:  # latexmk wrote main.pdf in place; publish it atomically
    shutil.copyfile(build / "main.pdf", tmp)
