"""Open reports in a real headless browser and check that they render.

For each report.html given (default: a fresh grasp-scene report of the
thesis's mean bird), Debian's chromium takes a full-page screenshot; the
check passes when the page is not blank: at least 1 % of the pixels differ
from the background and 0.1 % are coloured (the figures). Prints
a table and writes benchmarks/results/report_screenshot.json and the PNGs
beside it.

    apt-get install chromium            # once
    python benchmarks/report_screenshot.py [reports/hold_time/report.html ...]
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from matplotlib.image import imread

RESULTS = Path(__file__).parent / "results"
BROWSERS = ("chromium", "chromium-browser", "google-chrome")
#: a rendered report has text, tables and figures: on a 1200 x 4000 window the
#: shortest (a contact scene) measured 4.9 % non-background and 0.4 % coloured
#: pixels; a blank or unstyled page without figures has none coloured
MIN_INK, MIN_COLOURED = 0.01, 0.001


def browser() -> str:
    for name in BROWSERS:
        if shutil.which(name):
            return shutil.which(name)
    raise SystemExit("no chromium found: apt-get install chromium")


def screenshot(report: Path, png: Path, height: int = 4000) -> float:
    """Render ``report`` headless into ``png``; returns the wall time (s)."""
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as profile:
        subprocess.run([browser(), "--headless", "--no-sandbox", "--disable-gpu",
                        f"--user-data-dir={profile}", "--hide-scrollbars",
                        f"--window-size=1200,{height}", f"--screenshot={png}",
                        report.resolve().as_uri()],
                       check=True, capture_output=True, timeout=120)
    return time.perf_counter() - t0


def ink(png: Path) -> dict:
    """Share of pixels that are not the page background, and of coloured ones."""
    image = imread(png)[..., :3]
    background = np.median(image.reshape(-1, 3), axis=0)
    differs = np.abs(image - background).max(axis=-1) > 0.1
    coloured = (image.max(axis=-1) - image.min(axis=-1)) > 0.2
    return {"ink": float(differs.mean()), "coloured": float(coloured.mean()),
            "pixels": list(image.shape[:2])}


def default_report(folder: Path) -> Path:
    from design.api import simulate

    simulate(Path(__file__).parent.parent / "problems" / "grasp_mean_bird_hard.yaml", folder)
    return folder / "report.html"


def main(paths: list[str]) -> int:
    RESULTS.mkdir(exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        reports = [Path(p) for p in paths] or [default_report(Path(tmp))]
        rows = []
        for k, report in enumerate(reports):
            png = RESULTS / f"report_screenshot_{k}.png"
            seconds = screenshot(report, png)
            row = {"report": str(report), "screenshot": str(png), "wall_time_s": seconds,
                   **ink(png)}
            row["rendered"] = row["ink"] > MIN_INK and row["coloured"] > MIN_COLOURED
            rows.append(row)
    print(f"{'report':50s} {'ink':>6s} {'coloured':>9s} {'time (s)':>9s}  rendered")
    for r in rows:
        print(f"{r['report'][-50:]:50s} {r['ink']:6.3f} {r['coloured']:9.4f} "
              f"{r['wall_time_s']:9.2f}  {r['rendered']}")
    (RESULTS / "report_screenshot.json").write_text(json.dumps(rows, indent=1) + "\n")
    return 0 if all(r["rendered"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
