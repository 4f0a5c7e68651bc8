"""report.html opened in a real browser (headless Chromium, Debian's `chromium`; `make test`
installs it): it renders offline, its charts are inline images that decode, every table is
filled and answers its sort and filter controls, the console stays silent, and a screenshot of
the first screen is not blank.

The report is built from the committed fixture (tests/fixtures/results_small), as in
test_report.py. Skipped only where no Chromium is installed.
"""
import base64
import os
import re
import shutil
import struct
import subprocess
import sys

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
REPORT = os.path.join(ROOT, "plots", "report.py")
FIXTURE = os.path.join(ROOT, "tests", "fixtures", "results_small")
sys.path.insert(0, os.path.join(ROOT, "plots"))

import charts  # noqa: E402

BROWSER = next((shutil.which(b) for b in ("chromium", "chromium-browser") if shutil.which(b)), None)
pytestmark = pytest.mark.skipif(
    BROWSER is None, reason="no Chromium on PATH (Debian package `chromium`; `make test` "
                            "installs it through the Makefile's TEST_APT_PACKAGES)")
# The charts the fixture has data for (it ran on one thread).
DRAWN = [name for name in charts.CHARTS if name != "thread_scaling"]


def chromium(*args, timeout=120):
    """Runs headless Chromium; (stdout, the console lines of its log)."""
    # --no-sandbox: Chromium refuses to run as root with its sandbox, and CI containers often
    # lack the user namespaces it needs; the page is our own local file.
    flags = ["--headless", "--disable-gpu", "--no-first-run", "--disable-extensions",
             "--enable-logging=stderr", "--v=0", "--hide-scrollbars", "--no-sandbox"]
    proc = subprocess.run([BROWSER, *flags, *args], capture_output=True, text=True,
                          timeout=timeout)
    console = [line for line in proc.stderr.splitlines() if ":CONSOLE" in line]
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout, console


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    results = tmp_path_factory.mktemp("html") / "results_small"
    shutil.copytree(FIXTURE, results, ignore=shutil.ignore_patterns("*.py"))
    proc = subprocess.run([sys.executable, REPORT, str(results), "--strict"], capture_output=True,
                          text=True, env=dict(os.environ, MPLBACKEND="Agg"), timeout=300)
    assert proc.returncode == 0, proc.stderr
    return results / "report"


def test_report_html_is_self_contained(report):
    """No resource is fetched from anywhere: no http(s) URL in a src or href, no script or
    style file, and every chart inline."""
    page = (report / "report.html").read_text(encoding="utf-8")
    assert not re.search(r"""(src|href)=["']https?:""", page)
    assert "<script src" not in page and "<link " not in page
    for name in DRAWN:
        assert f"{name}.png" not in re.findall(r'src="([^"]+)"', page), name
    images = re.findall(r'<img class="chart" alt="([^"]*)" src="data:image/png;base64,([^"]+)"',
                        page)
    assert len(images) == len(DRAWN)
    for alt, data in images:
        png = base64.b64decode(data)
        assert png[:8] == b"\x89PNG\r\n\x1a\n", alt
        width, height = struct.unpack(">II", png[16:24])
        assert width > 300 and height > 200, (alt, width, height)


def test_report_html_renders_in_chromium(report):
    """The DOM after the page's script ran: every table set up (sort and filter controls added),
    filled, and no console message (an exception in the script would be one)."""
    page = report / "report.html"
    dom, console = chromium("--virtual-time-budget=5000", "--dump-dom", page.as_uri())
    assert console == [], console
    source = page.read_text(encoding="utf-8")
    n_tables = source.count('<table class="report"')
    assert n_tables >= 5
    assert f'data-tables-ready="{n_tables}"' in dom
    assert dom.count('data-ready="1"') == n_tables
    for table in re.findall(r'<table class="report".*?</table>', dom, re.S):
        assert re.search(r"<tbody>\s*<tr>\s*<td[ >]", table), table[:300]
    # Filter controls: one drop-down per model / query / path / method column; the headline
    # table's model filter offers the fixture's two models.
    first = re.search(r'<div class="filters">(.*?)</div>', dom, re.S).group(1)
    assert re.search(r'<option value="cow">cow</option>', first)
    assert re.search(r'<option value="fandisk">fandisk</option>', first)
    assert "Query: all" in first and "Path: all" in first
    assert dom.count('<img class="chart"') == len(DRAWN)


PROBE = """<!DOCTYPE html><html><body><iframe id="r" src="report.html" width="1200"
height="800"></iframe><script>
document.getElementById("r").addEventListener("load", function () {
  var d = this.contentDocument, out = {};
  var table = d.querySelector("table.report");
  var rows = function () {
    return Array.prototype.filter.call(table.tBodies[0].rows,
      function (r) { return r.style.display !== "none"; });
  };
  out.all = rows().length;
  var sel = d.querySelector(".filters select");          // the first table's model filter
  sel.value = "cow"; sel.dispatchEvent(new Event("change"));
  out.cow = rows().length;
  out.cowModels = rows().map(function (r) { return r.cells[0].textContent; }).join(",");
  sel.value = ""; sel.dispatchEvent(new Event("change"));
  var box = d.querySelector(".filters input");
  box.value = "distance"; box.dispatchEvent(new Event("input"));
  out.distance = rows().length;
  box.value = ""; box.dispatchEvent(new Event("input"));
  var rate = table.tHead.rows[0].cells[5];              // "Rate": sorted as numbers with units
  rate.click(); rate.click();                           // descending
  out.rates = rows().map(function (r) { return r.cells[5].textContent; }).join(",");
  document.body.setAttribute("data-probe", JSON.stringify(out));
});
</script></body></html>"""


def _hz(text):
    value, unit = re.match(r"([\d.]+)\s*(\w*)Hz", text).groups()
    return float(value) * {"": 1, "k": 1e3, "M": 1e6, "G": 1e9}[unit]


def test_report_html_tables_sort_and_filter(report):
    """The page's controls driven from a page beside it (an iframe, same folder): the model
    filter keeps only that model's rows, the text filter only matching rows, and a click on a
    rate column sorts by value (with its unit), not as text."""
    import json
    probe = report / "probe.html"
    probe.write_text(PROBE, encoding="utf-8")
    dom, console = chromium("--allow-file-access-from-files", "--virtual-time-budget=5000",
                            "--dump-dom", probe.as_uri())
    assert console == [], console
    m = re.search(r"data-probe=\"([^\"]*)\"", dom)
    assert m, "the probe did not run: " + dom[:500]
    out = json.loads(m.group(1).replace("&quot;", '"'))
    md = (report / "report.md").read_text(encoding="utf-8")
    headline = md.split("## Fastest exact method per model and query")[1].split("\n## ")[0]
    rows = [line for line in headline.splitlines() if line.startswith("| ") and "---" not in line][1:]
    assert out["all"] == len(rows)
    assert out["cow"] == sum(1 for r in rows if r.startswith("| cow |")) and out["cow"] > 0
    assert set(out["cowModels"].split(",")) == {"cow"}
    assert out["distance"] == sum(1 for r in rows if "| distance |" in r) > 0
    rates = [_hz(t) for t in out["rates"].split(",")]
    assert rates == sorted(rates, reverse=True) and len(rates) == len(rows)


def test_report_html_screenshot_is_not_blank(report, tmp_path):
    """The first screen as Chromium paints it: not blank (mostly white with text, tables and a
    chart: many distinct colours, a good share of non-white pixels)."""
    import numpy as np
    from matplotlib import image
    shot = tmp_path / "first_screen.png"
    _, console = chromium("--window-size=1400,1000", f"--screenshot={shot}",
                          (report / "report.html").as_uri())
    assert console == [], console
    assert shot.is_file() and shot.stat().st_size > 10_000
    px = image.imread(str(shot))[..., :3]
    assert px.shape[0] >= 900 and px.shape[1] >= 1300
    non_white = (px < 0.95).any(axis=2).mean()
    assert 0.03 < non_white < 0.9, non_white
    colours = len(np.unique((px * 255).astype(np.uint8).reshape(-1, 3), axis=0))
    assert colours > 50, colours
