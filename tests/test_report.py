"""The HTML report and the results files of servotune.report.

The job is the paper's two-mass system of sec 4.1 (Fig 5) tuned for C alone: every figure the
report names is written and embedded byte for byte, the numbers of its tables are the job's and
the closed forms of the paper (Copt = sqrt(K M1) f(alpha), peak g(alpha)/K, written out in
two_mass_reference),
odd names are escaped, and no file is overwritten unless asked.
"""

import base64
import dataclasses
import io
import math
import re
from html.parser import HTMLParser
from pathlib import Path

import matplotlib.image
import pytest
import two_mass_reference as ref

from servotune.axis import load_axis
from servotune.design import tune_axis
from servotune.report import (
    OutputExistsError,
    html_page,
    tuning_figures,
    write_atomically,
    write_html_report,
    write_json,
    write_tuning_files,
)

MODELS = Path(__file__).resolve().parents[1] / "models"
C_OPT, PEAK = ref.c_opt(), ref.g() / ref.K


class _Page(HTMLParser):
    """Images (alt, src) and tables (title of the preceding heading, rows of cell texts)."""

    def __init__(self):
        super().__init__()
        self.images, self.tables, self.headings = [], {}, []
        self._heading = self._cell = None
        self._rows = None

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "img":
            self.images.append((attrs.get("alt"), attrs.get("src")))
        elif tag in ("h1", "h2", "h3"):
            self._heading = ""
        elif tag == "table":
            self._rows = []
            self.tables[self.headings[-1] if self.headings else ""] = self._rows
        elif tag == "tr" and self._rows is not None:
            self._rows.append([])
        elif tag in ("td", "th") and self._rows is not None:
            self._cell = ""

    def handle_endtag(self, tag):
        if tag in ("h1", "h2", "h3") and self._heading is not None:
            self.headings.append(self._heading)
            self._heading = None
        elif tag in ("td", "th") and self._cell is not None:
            self._rows[-1].append(self._cell)
            self._cell = None
        elif tag == "table":
            self._rows = None

    def handle_data(self, data):
        if self._heading is not None:
            self._heading += data
        if self._cell is not None:
            self._cell += data


def _parse(text):
    page = _Page()
    page.feed(text)
    return page


def _png(data: bytes):
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return matplotlib.image.imread(io.BytesIO(data), format="png")


@pytest.fixture(scope="module")
def job():
    return tune_axis(load_axis(MODELS / "two_mass_fig5"), starts=1)


def test_every_figure_written_is_embedded_byte_for_byte(job, tmp_path):
    figures = tuning_figures(job)
    titles = [title for _, title, _ in figures]
    files = write_tuning_files(job, tmp_path)
    assert [f.name for f in files] == [name for name, _, _ in figures]
    assert {"compliance.png", "two_mass.png"} <= {f.name for f in files}
    for f in files:
        assert f.parent == tmp_path and _png(f.read_bytes()).shape[0] > 100
    report = write_html_report(job, tmp_path, figures=list(zip(files, titles, strict=True)))
    assert report == tmp_path / "report.html"
    page = _parse(report.read_text())
    assert [alt for alt, _ in page.images] == titles
    for (_, src), f in zip(page.images, files, strict=True):
        prefix = "data:image/png;base64,"
        assert src.startswith(prefix)
        assert base64.b64decode(src[len(prefix):]) == f.read_bytes()


def test_a_report_without_written_figures_draws_and_embeds_them(job, tmp_path):
    page = _parse(write_html_report(job, tmp_path).read_text())
    assert len(page.images) == len(tuning_figures(job))
    for _, src in page.images:
        image = _png(base64.b64decode(src.split(",", 1)[1]))
        assert image.shape[0] > 100 and image.shape[1] > 100


def test_the_tables_hold_the_job_and_the_closed_forms(job, tmp_path):
    page = _parse(write_html_report(job, tmp_path).read_text())
    two = {row[0]: row[1:] for row in page.tables[
        "Optimiser against the fixed-point theory (sec 4.1)"][1:]}
    closed, tuned, difference = (float(x) for x in two["Copt [N s/m]"])
    assert closed == pytest.approx(C_OPT, rel=1e-6)  # printed with 7 digits
    assert closed == pytest.approx(ref.COPT_PAPER, rel=1e-4)  # the paper's Fig 5
    assert tuned == pytest.approx(job.design.c, rel=1e-6)
    assert difference == pytest.approx(job.design.c / C_OPT - 1, abs=1e-6)
    closed, tuned, _ = (float(x) for x in two["peak g(alpha)/K [m/N]"])
    assert closed == pytest.approx(PEAK, rel=1e-6)
    assert tuned == pytest.approx(job.result.after.peak_compliance, rel=1e-6)
    design = {row[0]: row[1:] for row in page.tables["Design"][1:]}
    before, after = (float(x) for x in design["C guide ways [N s/m]"])
    assert before == pytest.approx(job.result.initial.c, rel=5e-4)  # 4 significant digits
    assert after == pytest.approx(job.design.c, rel=5e-4)
    peak_before, peak_after = (float(x) for x in design["worst compliance peak [m/N]"])
    assert peak_after == pytest.approx(PEAK, rel=5e-4)
    assert peak_before == pytest.approx(job.result.before.peak_compliance, rel=5e-4)
    # the peak is at the second fixed point
    f2 = ref.fixed_points()[1] / (2 * math.pi)
    assert float(design["  at [Hz]"][1]) == pytest.approx(f2, abs=0.05)  # printed to 0.1 Hz


def test_odd_names_are_escaped(job, tmp_path):
    name = '<script>alert("x")</script> & co'
    odd = dataclasses.replace(job, axis=dataclasses.replace(
        job.axis, name=name, description="a < b & c > d"))
    text = write_html_report(odd, tmp_path).read_text()
    assert "<script>" not in text and "a < b" not in text
    page = _parse(text)
    assert page.headings[0] == f"Feed-axis tuning: {name}"  # the text a browser shows
    assert re.search(r"<title>servotune: &lt;script&gt;alert\(&quot;x&quot;\)&lt;/script&gt; "
                     r"&amp; co</title>", text)
    assert "a &lt; b &amp; c &gt; d" in text
    assert html_page("<b>", "<p>body</p>").count("&lt;b&gt;") == 1


def test_results_are_not_overwritten_unless_asked(tmp_path):
    path = write_json(tmp_path / "sub" / "results.json", {"c": 1.5})
    assert path.read_text() == '{\n  "c": 1.5\n}\n'
    with pytest.raises(OutputExistsError, match=r"results\.json exists; pass --force"):
        write_atomically(path, "other")
    assert path.read_text() == '{\n  "c": 1.5\n}\n'
    write_atomically(path, b"new", force=True)
    assert path.read_bytes() == b"new"
    assert sorted(p.name for p in path.parent.iterdir()) == ["results.json"]  # no temp file
