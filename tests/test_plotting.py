"""The rule-graph drawing (no Graphviz): layers from the DOT edges, an error on bad input."""

import pytest

from railradio.plotting import plot_rulegraph

DOT = """digraph snakemake_dag {
	0[label = "all", color = "0.00 0.6 0.85", style="rounded"];
	1[label = "fusion_figure", color = "0.05 0.6 0.85", style="rounded"];
	2[label = "fusion_point", color = "0.08 0.6 0.85", style="rounded"];
	1 -> 0
	2 -> 1
}"""


def test_rulegraph_png(tmp_path):
    out = tmp_path / "g.png"
    plot_rulegraph(DOT, str(out))
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ValueError, match="no nodes"):
        plot_rulegraph("digraph {}", str(tmp_path / "x.png"))
