"""Measurement hook for rules without a ``benchmark:`` (see ../derive_resources.py).

Put this directory on PYTHONPATH and set SCALE_MEMLOG=<file>: every Snakemake job script
then appends its rule, wall time and peak RSS (getrusage) as one JSON line when it exits.
Linux's ru_maxrss of a process includes the RSS of the forked Snakemake process at exec
(about 260 MB here), so small scripts read high: an upper bound, safe for a memory limit.
"""

import atexit
import json
import os
import resource
import sys
import time

_T0_S = time.time()


def _record() -> None:
    smk = getattr(sys.modules.get("__main__"), "snakemake", None)
    if smk is None or "SCALE_MEMLOG" not in os.environ:
        return
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    with open(os.environ["SCALE_MEMLOG"], "a", encoding="utf-8") as fh:
        fh.write(
            json.dumps(
                {
                    "rule": smk.rule,
                    "wall_s": time.time() - _T0_S,
                    "maxrss_mb": own.ru_maxrss / 1024,
                    "child_maxrss_mb": kids.ru_maxrss / 1024,
                    "cpu_s": own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime,
                }
            )
            + "\n"
        )


atexit.register(_record)
