"""The built documentation site, opened in headless Chromium: figures shown, no broken internal link.

The site is built by ``sphinx-build -W --keep-going -b html docs docs/_build/html`` (``.ci/run`` builds
it, then runs this file with ``TOOLIMIT_DOCS_REQUIRED=1``). Without a built site the tests skip with
that reason, unless ``TOOLIMIT_DOCS_REQUIRED`` is set; ``TOOLIMIT_DOCS_HTML`` points at another build.

The site is served on 127.0.0.1 only, and Debian's ``chromium`` (no browser download) loads a
harness page from the same origin that opens every page in a frame and records, after its images
have loaded: the images shown (decoded, non-zero width) and broken, the inline SVGs of notebook
outputs, and every internal link; then each linked page is fetched, and a link's ``#fragment`` must
name an element of it. Checked: every notebook page shows at least one figure, every results page
(but its index) a chart, no image is broken, no internal link or fragment is, and no page loads a
script, style or font from the network.
"""

from __future__ import annotations

import functools
import http.server
import json
import os
import re
import shutil
import subprocess
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SITE = Path(os.environ.get("TOOLIMIT_DOCS_HTML", REPO / "docs" / "_build" / "html"))
#: Chromium's flags: headless, no network of its own, a fresh profile (added per run).
CHROMIUM_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
)
#: Harness page's budget of (virtual) time, ms: every page, its images and every linked page.
TIME_BUDGET_MS = 600_000
#: An external resource a page would load (not a link the reader may follow).
EXTERNAL_RESOURCE = re.compile(r"<(?:script|link|img|iframe)\b[^>]*(?:src|href)=\"(?:https?:)?//[^\"]+\"", re.I)

HARNESS = """<!doctype html><html><body><pre id="result">pending</pre><script>
const PAGES = %s;
async function opened(url) {
  const frame = document.createElement("iframe");
  frame.style.width = "1200px"; frame.style.height = "900px";
  const loaded = new Promise(resolve => frame.onload = resolve);
  frame.src = url; document.body.appendChild(frame); await loaded;
  return frame;
}
async function main() {
  const pages = {}, links = new Set();
  for (const page of PAGES) {
    const frame = await opened(page);
    const doc = frame.contentDocument;
    const images = [...doc.querySelectorAll("article img")];
    await Promise.all(images.map(i => i.complete ? null : new Promise(r => { i.onload = r; i.onerror = r; })));
    for (const a of doc.querySelectorAll("a[href]")) {
      const url = new URL(a.getAttribute("href"), frame.contentWindow.location.href);
      if (url.origin === location.origin) links.add(url.href);
    }
    pages[page] = {
      shown: images.filter(i => i.naturalWidth > 0).map(i => i.getAttribute("src")),
      broken: images.filter(i => !(i.naturalWidth > 0)).map(i => i.getAttribute("src")),
      output_svgs: doc.querySelectorAll("article .cell_output svg, article .output svg").length,
      output_images: [...doc.querySelectorAll("article .cell_output img")].filter(i => i.naturalWidth > 0).length,
    };
    frame.remove();
  }
  const bad = [], texts = {};
  for (const link of links) {
    const url = new URL(link), page = url.origin + url.pathname;
    if (!(page in texts)) {
      const response = await fetch(page);
      texts[page] = response.ok ? await response.text() : null;
    }
    if (texts[page] === null) { bad.push(link + " (not found)"); continue; }
    const id = decodeURIComponent(url.hash.slice(1));
    if (id && url.pathname.endsWith(".html")) {
      const target = new DOMParser().parseFromString(texts[page], "text/html");
      if (!target.getElementById(id) && !target.getElementsByName(id).length) bad.push(link + " (no such anchor)");
    }
  }
  document.getElementById("result").textContent = JSON.stringify({pages, bad_links: bad, links: links.size});
}
main().catch(error => { document.getElementById("result").textContent = "error: " + error; });
</script></body></html>
"""


def _required() -> bool:
    return bool(os.environ.get("TOOLIMIT_DOCS_REQUIRED"))


@pytest.fixture(scope="module")
def site() -> Path:
    if not (SITE / "index.html").is_file():
        if _required():
            pytest.fail(f"no built site at {SITE} (TOOLIMIT_DOCS_REQUIRED is set)")
        pytest.skip(
            f"no built site at {SITE}: build it with sphinx-build -W --keep-going -b html docs docs/_build/html"
        )
    return SITE


def _pages(site: Path, folder: str) -> list[str]:
    return sorted(str(p.relative_to(site)) for p in (site / folder).glob("*.html"))


@pytest.fixture(scope="module")
def browsed(site: Path) -> Iterator[dict]:
    """What the harness recorded for every page of the site (served on 127.0.0.1)."""
    chromium = shutil.which("chromium")
    if chromium is None:
        if _required():
            pytest.fail("Debian's chromium is not installed (apt-get install -y chromium)")
        pytest.skip("Debian's chromium is not installed (apt-get install -y chromium)")
    pages = sorted(
        str(p.relative_to(site))
        for p in site.rglob("*.html")
        if not p.relative_to(site).parts[0].startswith(("_", "."))
    )
    with tempfile.TemporaryDirectory() as scratch:
        served = Path(scratch) / "site"
        shutil.copytree(site, served)
        (served / "__harness.html").write_text(HARNESS % json.dumps(["/" + page for page in pages]))
        handler = functools.partial(_QuietHandler, directory=str(served))
        server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
        thread = threading.Thread(target=server.serve_forever, daemon=True)
        thread.start()
        try:
            url = f"http://127.0.0.1:{server.server_address[1]}/__harness.html"
            dom = subprocess.run(
                [
                    chromium,
                    *CHROMIUM_FLAGS,
                    f"--user-data-dir={Path(scratch) / 'profile'}",
                    f"--virtual-time-budget={TIME_BUDGET_MS}",
                    "--dump-dom",
                    url,
                ],
                capture_output=True,
                text=True,
                timeout=900,
                check=False,
            ).stdout
        finally:
            server.shutdown()
            thread.join()
    match = re.search(r'<pre id="result">(.*?)</pre>', dom, re.S)
    assert match, f"the harness page did not load in chromium:\n{dom[-2000:]}"
    text = match.group(1).replace("&quot;", '"').replace("&lt;", "<").replace("&gt;", ">").replace("&amp;", "&")
    assert not text.startswith(("pending", "error")), f"the harness did not finish: {text[:2000]}"
    yield json.loads(text)


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: object) -> None:  # noqa: A002
        pass


def test_every_page_was_opened(site: Path, browsed: dict):
    assert len(browsed["pages"]) >= 20 and "/index.html" in browsed["pages"]
    assert browsed["links"] > 50


def test_every_notebook_page_shows_its_figures(site: Path, browsed: dict):
    notebooks = _pages(site, "notebooks")
    assert len(notebooks) == len(list((REPO / "notebooks").glob("*.ipynb")))
    empty = [
        page
        for page in notebooks
        if browsed["pages"]["/" + page]["output_svgs"] + browsed["pages"]["/" + page]["output_images"] == 0
    ]
    assert not empty, f"notebook pages without a figure in their outputs: {empty}"
    unlabelled = [page for page in notebooks if "quick-budget" not in (site / page).read_text(encoding="utf-8")]
    assert not unlabelled, f"notebook pages that do not say their figures come from the quick budgets: {unlabelled}"


def test_every_results_page_shows_its_chart(site: Path, browsed: dict):
    results = [page for page in _pages(site, "results") if not page.endswith("index.html")]
    assert len(results) == 8
    chartless = [
        page
        for page in results
        if not any("_generated/" in src or src.endswith(".svg") for src in browsed["pages"]["/" + page]["shown"])
    ]
    assert not chartless, f"results pages without a chart shown: {chartless}"


def test_no_image_is_broken(browsed: dict):
    broken = {page: record["broken"] for page, record in browsed["pages"].items() if record["broken"]}
    assert not broken, f"images that did not load: {broken}"


def test_no_internal_link_is_broken(browsed: dict):
    assert not browsed["bad_links"], "broken internal links:\n" + "\n".join(browsed["bad_links"])


def test_no_page_loads_anything_from_the_network(site: Path):
    loading = {
        str(page.relative_to(site)): EXTERNAL_RESOURCE.findall(page.read_text(encoding="utf-8", errors="replace"))
        for page in site.rglob("*.html")
    }
    loading = {page: found for page, found in loading.items() if found}
    assert not loading, f"pages that load from the network: {loading}"
