import pytest

from railradio.keynumbers import KeySpec, claims_table, compare, format_number, merge, to_latex


def test_entry_and_merge():
    a = {"x.a": KeySpec("x.a", "m", "a thing", 1.3, "<").entry(1.2, 0.01)}
    b = {"y.b": KeySpec("y.b", "1", "b").entry(3.0)}
    m = merge([b, a])
    assert list(m) == ["x.a", "y.b"]
    assert m["x.a"] == {
        "value": 1.2,
        "unit": "m",
        "source_value": 1.3,
        "source_relation": "<",
        "description": "a thing",
        "mc_stderr": 0.01,
        "digits": 3,
    }
    with pytest.raises(ValueError, match="twice"):
        merge([a, a])


def test_spec_validation():
    with pytest.raises(ValueError):
        KeySpec("k", "m", "d", 1.0, None)
    with pytest.raises(ValueError):
        KeySpec("k", "m", "d", 1.0, "<<")
    with pytest.raises(ValueError, match="finite"):
        KeySpec("k", "m", "d").entry(float("nan"))


@pytest.mark.parametrize(
    ("v", "s"),
    [
        (15.126, "15.1"),
        (0.66, "0.660"),
        (3.0, "3"),
        (0.0025, "0.00250"),
        (123456.7, "123457"),
        (1.5e-7, r"\ensuremath{1.50\times10^{-7}}"),
        (None, "--"),
    ],
)
def test_format_number(v, s):
    assert format_number(v) == s


def test_latex_macros_and_claims():
    nums = {"fusion.d1500.rmse_tdoa_m": KeySpec("fusion.d1500.rmse_tdoa_m", "m", "TDOA σ", 2.0, "≤").entry(20.8)}
    tex = to_latex(nums)
    assert r"\@namedef{kn@fusion.d1500.rmse_tdoa_m}{20.8}" in tex
    assert r"\@namedef{knsrc@fusion.d1500.rmse_tdoa_m}{$\le\,$2}" in tex
    assert r"\PackageError" in tex  # undefined keys fail the build
    row = claims_table(nums)
    assert r"\kn{fusion.d1500.rmse_tdoa_m}" in row and r"d1500.\allowbreak{}rmse\_tdoa\_m" in row
    assert row.startswith(r"\begin{longtable}") and row.rstrip().endswith(r"\end{longtable}")
    assert r"\kn{" not in claims_table({"k": KeySpec("k", "m", "x").entry(1.0)}, with_source_only=True)


def test_statistical_comparison_uses_monte_carlo_errors():
    ref = {"k": {"value": 10.0, "mc_stderr": 0.1}}
    assert compare({"k": {"value": 10.3, "mc_stderr": 0.1}}, ref, mode="statistical") == []  # 2.1 sigma
    assert compare({"k": {"value": 10.7, "mc_stderr": 0.1}}, ref, mode="statistical")  # 4.9 sigma
    assert compare({}, ref) == ["k: missing from the new numbers"]
    assert compare({"k": {"value": 10.0}}, {"k": {"value": 10.0}}) == []


def test_reproduction_is_judged_by_the_precision_of_the_path_not_the_monte_carlo_error():
    """Same config and seed: the Monte Carlo error does not widen the tolerance; a key with
    a float32 stage (nr.*) is allowed 1e-5 relative, a float64 key 1e-9, never 1e-9 for
    float32."""
    from railradio.keynumbers import REL_TOL_FLOAT32, REL_TOL_FLOAT64, rel_tol, tolerance

    ref = {"k": {"value": 10.0, "mc_stderr": 0.1}}
    assert compare({"k": {"value": 10.3, "mc_stderr": 0.1}}, ref)  # 2 sigma is not rounding
    assert compare({"k": {"value": 10.0 + 5e-9}}, ref) == []
    assert compare({"k": {"value": 10.0 + 5e-8}}, ref)
    nr = {"nr.track.x": {"value": 10.0}}
    assert compare({"nr.track.x": {"value": 10.0 + 5e-5}}, nr) == []
    assert compare({"nr.track.x": {"value": 10.0 + 5e-4}}, nr)
    assert rel_tol("sens.nr.base.source.x") == rel_tol("chain.nr_ekf.err_m.rms") == REL_TOL_FLOAT32
    assert rel_tol("chain.joint.success.sigma0") == rel_tol("handover.a3.success.v350") == REL_TOL_FLOAT64
    assert REL_TOL_FLOAT32 > 1e3 * REL_TOL_FLOAT64
    assert tolerance("k", {"value": 0.0}, {"value": 0.0}) > 0  # an absolute floor at zero
    with pytest.raises(ValueError, match="mode"):
        compare({"k": {"value": 1.0}}, {"k": {"value": 1.0}}, mode="exact")


def test_tex_escape_is_ascii_and_pdflatex_safe():
    from railradio.keynumbers import _tex_escape

    got = _tex_escape("sqrt((e_h^2+e_t^2)/2) ~ 50% & #1 $x{y}\\ σ Δ Α ο → ≥ − ‰")
    assert got.isascii()
    assert r"e\_h\^{}2" in got and r"\~{}" in got and r"\%" in got and r"\$x\{y\}" in got
    assert r"$\sigma$" in got and r"$\Delta$" in got and r"$\to$" in got and r"$\ge$" in got
    assert r"$\Alpha$" not in got and r"$\omicron$" not in got  # no such LaTeX macros


def test_config_macros_cover_values_lists_and_list_elements():
    from railradio.keynumbers import config_to_latex

    tex = config_to_latex({"a": {"x": 2.5, "radii_m": [20000.0, 7000.0], "phases": [[1.0, 2.0]], "name": "TDL-D"}})
    assert r"\@namedef{cfg@a.x}{2.5}" in tex
    assert r"\@namedef{cfg@a.radii_m}{20000, 7000}" in tex
    assert r"\@namedef{cfgn@a.radii_m}{2}" in tex
    assert r"\@namedef{cfg@a.radii_m.0}{20000}" in tex and r"\@namedef{cfg@a.radii_m.1}{7000}" in tex
    assert "cfg@a.phases.0" not in tex  # elements only for lists of scalars
    assert r"\@namedef{cfg@a.name}{\texttt{TDL-D}}" in tex


def test_the_reports_table_sets_ours_beside_the_sources_value():
    from railradio.keynumbers import KeySpec, claims_html

    numbers = {
        "nr.a": KeySpec("nr.a", "m", "RMSE <of> x", source_value=2.5, source_relation="<").entry(1.234),
        "nr.b": KeySpec("nr.b", "m", "no claim").entry(3.0),
        "handover.c": KeySpec("handover.c", "1", "rate", source_value=0.9, source_relation="≈").entry(0.95),
    }
    html = claims_html(numbers)
    assert "<h2>nr</h2>" in html and "<h2>handover</h2>" in html
    row = html.split("<code>nr.a</code>")[1].split("</tr>")[0]
    assert "RMSE &lt;of&gt; x" in row and "&lt; 2.5" in row and "1.23" in row
    assert "nr.b" not in html  # no source value: not in the table
