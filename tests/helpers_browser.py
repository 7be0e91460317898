"""Open a report in headless Chromium and read what a reader would see: every image loaded, no script
error, and where the decision box sits in a 1366 x 768 window."""

from __future__ import annotations

import json
import re
import subprocess
import tempfile
from pathlib import Path

from conftest import require_tool

WINDOW = (1366, 768)
# appended to a copy of the page: records, after load, each image's natural size, script errors, and the
# decision box's position, into an attribute --dump-dom prints
PROBE = """<script>
window.__errors = [];
window.addEventListener('error', e => window.__errors.push(String(e.message || e)));
window.addEventListener('load', () => {
  const box = document.getElementById('decision');
  const r = box ? box.getBoundingClientRect() : null;
  const out = {images: [...document.images].map(i => ({alt: i.alt, complete: i.complete, width: i.naturalWidth})),
               errors: window.__errors, viewport: [window.innerWidth, window.innerHeight],
               decision: r ? {top: r.top, bottom: r.bottom, left: r.left, right: r.right, text: box.innerText} : null};
  document.documentElement.setAttribute('data-probe', JSON.stringify(out));
});
</script>"""


def probe_page(html: Path) -> dict:
    """What Chromium sees of `html` (see PROBE), with its console errors from stderr."""
    chromium = require_tool("chromium", "Debian: apt-get install chromium")
    with tempfile.TemporaryDirectory() as tmp:
        page = Path(tmp) / "page.html"
        page.write_text(html.read_text().replace("</body>", PROBE + "</body>"))
        result = subprocess.run(
            [chromium, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync",
             f"--user-data-dir={tmp}/profile", f"--window-size={WINDOW[0]},{WINDOW[1]}", "--hide-scrollbars",
             "--virtual-time-budget=10000", "--enable-logging=stderr", "--v=0", "--dump-dom", page.as_uri()],
            capture_output=True, text=True, timeout=120)
    found = re.search(r"data-probe=\"([^\"]*)\"", result.stdout)
    assert found, f"Chromium did not run the page's probe (exit {result.returncode}): {result.stderr[-2000:]}"
    data = json.loads(found.group(1).replace("&quot;", '"').replace("&amp;", "&").replace("&lt;", "<").replace("&gt;", ">"))
    data["console_errors"] = [line for line in result.stderr.splitlines() if "CONSOLE" in line and "ERROR" in line.upper()]
    return data


def assert_readable(html: Path) -> dict:
    """The page renders without errors, every image loads, and the decision is in the first screen."""
    seen = probe_page(html)
    assert not seen["errors"] and not seen["console_errors"], (seen["errors"], seen["console_errors"])
    assert seen["images"], "the report has no images"
    broken = [i["alt"] for i in seen["images"] if not (i["complete"] and i["width"] > 0)]
    assert not broken, f"images that did not load: {broken}"
    d = seen["decision"]
    assert d is not None, "no decision box (id='decision')"
    assert d["text"].strip(), "the decision box is empty"
    width, height = seen["viewport"]
    assert 0 <= d["top"] and d["bottom"] <= height and d["right"] <= width, (d, seen["viewport"])
    return seen
