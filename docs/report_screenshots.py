"""Regenerate the screenshots of docs/report.md: three bundled runs reported, each page shot in Chromium.

* ``report-pokeys-stall.png``: a PoKeys hazard (``pokeys_stall``: the buffer drains into an underrun);
* ``report-trio-gate.png``: a Trio gate (``trio_example``: the laser gated at exact step counts);
* ``report-pmac-time-base.png``: a PMAC time base (``pmac_external_time_base``).

Each shot is the top of the page (verdict, checks) and its waveform as the page opens. Needs the
Debian ``chromium`` (``tasks.py test`` installs it). Run from the checkout::

    .venv/bin/python docs/report_screenshots.py
"""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

DOCS = Path(__file__).resolve().parent
#: scenario -> picture, and the URL fragment the page is opened with ("" for the view it opens on).
SHOTS = {
    "pokeys_stall": ("report-pokeys-stall.png", ""),
    "trio_example": ("report-trio-gate.png", ""),
    "pmac_external_time_base": ("report-pmac-time-base.png", ""),
}


def main() -> None:
    from playwright.sync_api import sync_playwright

    from cosim.catalog import load
    from cosim.report import write_report
    from cosim.runner import run_scenario

    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        sys.exit("chromium is not installed (apt-get install chromium)")
    with tempfile.TemporaryDirectory(prefix="cosim-shots-") as folder:
        out = Path(folder)
        scenarios = [load(name) for name in SHOTS]
        results = [run_scenario(s, out=out / s.name) for s in scenarios]
        write_report(results, out, scenarios=scenarios)
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=chromium, headless=True)
            for name, (picture, fragment) in SHOTS.items():
                page = browser.new_page(viewport={"width": 1300, "height": 900})
                page.goto((out / name / "index.html").resolve().as_uri() + fragment)
                page.wait_for_function("window.cosimWave && window.cosimWave.drawn === true")
                bottom = page.evaluate("(() => { const r = document.getElementById('cosim-plot')"
                                       ".getBoundingClientRect(); return r.bottom + window.scrollY + 8; })()")
                page.screenshot(path=str(DOCS / picture), full_page=True,
                                clip={"x": 0, "y": 0, "width": 1300, "height": bottom})
                page.close()
                print(f"wrote {DOCS / picture}")
            browser.close()


if __name__ == "__main__":
    main()
