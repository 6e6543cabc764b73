"""The report as one HTML page (issue 11.3): converter, and the page in headless Chromium."""

import html.parser
import json
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest

from ppamsafety.report.html import inline, markdown_to_html, report_page

REPORTS = Path(__file__).parent.parent / "reports"


class _Collect(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.tags, self.imgs, self.stack, self.rows = [], [], [], []

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        if tag == "img":
            self.imgs.append(dict(attrs)["src"])
        if tag == "tr":
            self.rows.append(0)
        if tag in ("td", "th"):
            self.rows[-1] += 1


def test_markdown_subset_converts():
    md = ("# Title\n\nSome *italic*, **bold** and `a<b` with p_m and F_max.\n\n"
          "| a | b |\n|---|---|\n| 1 | *x* |\n| 2 |  |\n\n* one\n* two\n  continued\n\n"
          "1. first\n2. second\n\n![fig](f.png)\n\n## Sec\n\n```\n<raw> *no*\n```\n")
    body, toc = markdown_to_html(md)
    assert toc == [(1, "title", "Title"), (2, "sec", "Sec")]
    assert "<em>italic</em>" in body and "<strong>bold</strong>" in body
    assert "<code>a&lt;b</code>" in body and "p_m and F_max" in body        # no _emphasis_
    assert "<thead><tr><th>a</th><th>b</th></tr></thead>" in body
    assert "<tr><td>2</td><td></td></tr>" in body and "<td><em>x</em></td>" in body
    assert "<ul><li>one</li><li>two continued</li></ul>" in body
    assert "<ol><li>first</li><li>second</li></ol>" in body
    assert '<img src="f.png" alt="fig"' in body
    assert "<pre><code>&lt;raw&gt; *no*</code></pre>" in body
    assert inline("<script>") == "&lt;script&gt;"                           # never raw HTML


def test_the_committed_report_converts_completely():
    md = (REPORTS / "index.md").read_text(encoding="utf-8")
    page = report_page(md)
    p = _Collect()
    p.feed(page)
    n_tables = len(re.findall(r"^\|?\s*-{3,}", md, flags=re.M))
    assert p.tags.count("table") == n_tables > 10
    assert len(p.imgs) == md.count("![") and all((REPORTS / s).is_file() for s in p.imgs)
    sections = re.findall(r"^## (.+)$", md, flags=re.M)
    assert page.count('<a class="h2"') == len(sections) >= 8                # navigation
    assert "Table 6.1 reproduced" in page and "HIC_ratio" in page          # ours, thesis, ratio


CHECK = """<script>
window.addEventListener('load', function () {
  var imgs = Array.from(document.images);
  var bad = imgs.filter(function (i) { return !(i.complete && i.naturalWidth > 0); });
  var tables = Array.from(document.querySelectorAll('table'));
  var badt = tables.filter(function (t) {
    var n = t.tHead ? t.tHead.rows[0].cells.length : 0;
    return n === 0 || t.tBodies.length !== 1 || t.tBodies[0].rows.length === 0 ||
      Array.from(t.tBodies[0].rows).some(function (r) { return r.cells.length !== n; }); });
  var d = document.createElement('pre'); d.id = 'verdict';
  d.textContent = JSON.stringify({images: imgs.length, widths: imgs.map(function (i) {
    return i.naturalWidth; }), bad_images: bad.map(function (i) { return i.getAttribute('src'); }),
    tables: tables.length, bad_tables: badt.length});
  document.body.appendChild(d);
});
</script>"""


def _chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        exe = shutil.which(name)
        if exe:
            return exe
    return None


def _verdict(dom: str) -> dict:
    m = re.search(r'<pre id="verdict">([^<]*)</pre>', dom)
    assert m, f"the page's check did not run: {dom[:300]!r}"
    return json.loads(m.group(1).replace("&quot;", '"'))


@pytest.mark.skipif(_chromium() is None, reason="headless Chromium is not installed "
                    "(apt-get install chromium)")
def test_report_page_in_headless_chromium(tmp_path):
    """Every image loads (naturalWidth > 0), every table parses; a screenshot is taken."""
    for f in REPORTS.glob("*.png"):
        shutil.copy(f, tmp_path / f.name)
    page = report_page((REPORTS / "index.md").read_text(encoding="utf-8"))
    (tmp_path / "index.html").write_text(page.replace("</body>", CHECK + "</body>"),
                                         encoding="utf-8")       # a test-only copy of the page
    flags = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
             "--disable-component-update", "--disable-sync", "--no-first-run",
             "--virtual-time-budget=15000"]
    url = (tmp_path / "index.html").as_uri()
    with tempfile.TemporaryDirectory() as prof:
        dom = subprocess.run([_chromium(), *flags, f"--user-data-dir={prof}", "--dump-dom", url],
                             capture_output=True, text=True, timeout=180).stdout
    v = _verdict(dom)
    assert v["images"] == page.count("<img") and v["bad_images"] == []
    assert min(v["widths"]) > 0
    assert v["tables"] == page.count("<table>") and v["bad_tables"] == 0
    # the check itself catches a missing image and a ragged table
    bad = report_page("![gone](missing.png)\n\n| a | b |\n|---|---|\n| 1 |\n")
    (tmp_path / "bad.html").write_text(bad.replace("</body>", CHECK + "</body>"))
    with tempfile.TemporaryDirectory() as prof:
        dom = subprocess.run([_chromium(), *flags, f"--user-data-dir={prof}", "--dump-dom",
                              (tmp_path / "bad.html").as_uri()],
                             capture_output=True, text=True, timeout=180).stdout
    assert _verdict(dom)["bad_images"] == ["missing.png"]
    shot = tmp_path / "screenshot.png"
    with tempfile.TemporaryDirectory() as prof:
        subprocess.run([_chromium(), *flags, f"--user-data-dir={prof}", "--window-size=1400,1000",
                        f"--screenshot={shot}", url], capture_output=True, timeout=180)
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and shot.stat().st_size > 20_000
