"""Report rendering: HTML is self-contained, Markdown mirrors it."""

import matplotlib.pyplot as plt

from bayesupdate.report.document import Document, Figure, Section, Table, fmt
from bayesupdate.report.render import write_report


def test_html_embeds_figures_and_markdown_links_them(tmp_path):
    fig, ax = plt.subplots(figsize=(2, 2))
    ax.plot([0, 1], [0, 1])
    fig.savefig(tmp_path / "line.png")
    plt.close(fig)
    doc = Document(
        "Study",
        "sub",
        (
            Section(
                "Results",
                (
                    "Expr < 0.05 & mass ok",
                    Table(("mode", "f [Hz]"), ((1, 9.19), (2, 11.74)), caption="Table 2"),
                    Figure("line.png", "a line"),
                ),
            ),
        ),
    )
    html_path, md_path = write_report(doc, tmp_path)
    page = html_path.read_text()
    assert "data:image/png;base64," in page and "line.png" not in page
    assert "Expr &lt; 0.05 &amp; mass ok" in page and "<td>11.74</td>" in page
    md = md_path.read_text()
    assert "| mode | f [Hz] |" in md and "| 2 | 11.74 |" in md and "![a line](line.png)" in md


def test_fmt():
    assert fmt(0.040227) == "0.04023" and fmt(12.29) == "12.29" and fmt(3) == "3"
    assert fmt(1.5e-7) == "1.500e-07" and fmt(None) == "-" and fmt(True) == "yes"


def test_an_unconverged_posterior_gets_a_visible_warning(tmp_path):
    from types import SimpleNamespace

    from bayesupdate.report.demo_report import _convergence_warning
    from bayesupdate.report.document import Alert

    reason = "R-hat 1.029 > 1.01 (t_cold_pipe); step budget reached after 2500 steps"
    stuck = SimpleNamespace(converged=False, diagnostics={"convergence": {"reason": reason}})
    done = SimpleNamespace(converged=True, diagnostics={"convergence": {"reason": None}})
    assert _convergence_warning(done) == ()
    (alert,) = _convergence_warning(stuck)
    assert isinstance(alert, Alert) and reason in alert.text
    doc = Document("t", "s", (Section("posterior", (alert,)),))
    html_path, md_path = write_report(doc, tmp_path)
    assert "<p class='warning'>Warning: this posterior did not converge: R-hat 1.029" in (
        html_path.read_text()
    )
    assert "> **Warning:** this posterior did not converge" in md_path.read_text()
