"""The `rcsc doc` page at desktop and phone width in headless Chromium: no
horizontal overflow of the page (wide tables and pictures scroll in their
own boxes), and no picture text shrunk below 8 px (a large picture is shown
at its own size, scrolling, instead of as an unreadable thumbnail).
Screenshots are kept in build/doc-screenshots/ for a person to look at."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from rcsc.outputs import doc
from test_doc import EXAMPLES, SCREENSHOTS, checked, chromium, need

# Measured after the page's own load handlers: the page's overflow, and the
# smallest on-screen size of any picture text (font size times the SVG's scale).
MEASURE = """<script>
window.addEventListener("load", function () { setTimeout(function () {
  var root = document.documentElement, min = 1e9;
  var texts = document.querySelectorAll(".picture svg text");
  for (var i = 0; i < texts.length; i++) {
    var t = texts[i], ctm = t.getScreenCTM();
    var size = parseFloat(getComputedStyle(t).fontSize) * (ctm ? Math.hypot(ctm.a, ctm.b) : 1);
    if (size < min) { min = size; }
  }
  root.setAttribute("data-overflow", String(root.scrollWidth - root.clientWidth));
  root.setAttribute("data-min-text", String(Math.round(min * 10) / 10));
  root.setAttribute("data-wide", String(document.querySelectorAll(".picture.wide").length));
}, 0); });
</script></body>"""


@pytest.mark.parametrize("width", [1400, 390])
@pytest.mark.parametrize("example", list(EXAMPLES))
def test_page_fits_and_text_stays_readable(example: str, width: int, tmp_path: Path) -> None:
    need("dot")
    index = doc.write_site(checked(example).model, checked(example).diags.items, str(tmp_path / "site"))
    probe = tmp_path / "probe.html"
    probe.write_text(index.read_text(encoding="utf-8").replace("</body>", MEASURE), encoding="utf-8")
    dom = chromium([f"--window-size={width},900", "--virtual-time-budget=3000", "--dump-dom", probe.resolve().as_uri()],
                   tmp_path / "profile")
    assert dom.returncode == 0, dom.stderr[-2000:]
    found = dict(re.findall(r'data-(overflow|min-text|wide)="([^"]*)"', dom.stdout))
    assert set(found) == {"overflow", "min-text", "wide"}, "the measuring script did not run"
    assert int(found["overflow"]) <= 0, f"the page is {found['overflow']} px wider than a {width} px window"
    assert float(found["min-text"]) >= 8.0, f"picture text shrinks to {found['min-text']} px at {width} px"
    if width == 390:
        assert int(found["wide"]) > 0  # on a phone some pictures scroll instead of shrinking
    shot = tmp_path / f"{example}-{width}.png"
    run = chromium([f"--screenshot={shot}", f"--window-size={width},2400", index.resolve().as_uri()], tmp_path / "profile-shot")
    assert run.returncode == 0 and shot.read_bytes().startswith(b"\x89PNG")
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(shot, SCREENSHOTS / shot.name)
