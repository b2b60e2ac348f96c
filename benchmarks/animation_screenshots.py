"""Open a report's 3-D animation in headless Chromium: time the page's load,
step the animation to three instants and screenshot each; measure how many
frames a second it plays at 1x.

    apt-get install chromium            # once
    python -m benchmarks.animation_screenshots reports/hold_time/report.html \\
        [--times 0.6 1.0 1.2] [--out docs/img]

Prints the report's size, the load time (navigation to the figure drawn,
the median of three loads), the frame rate, and writes
``<out>/animation_t<time>.png`` and ``benchmarks/results/animation_view.json``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

from tests.test_reports_animation import CHROMIUM, CHROMIUM_FLAGS

RESULTS = Path(__file__).parent / "results"
VIEW = "document.getElementById('animation-view')"
#: how long the frame-rate measurement plays at 1x (s)
PLAY_S = 3.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("report", type=Path)
    parser.add_argument("--times", type=float, nargs=3, default=(0.6, 1.0, 1.2))
    parser.add_argument("--out", type=Path, default=Path("docs/img"))
    args = parser.parse_args()
    from playwright.sync_api import sync_playwright

    args.out.mkdir(parents=True, exist_ok=True)
    url = args.report.resolve().as_uri()
    loads, shots = [], []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_FLAGS)
        for _ in range(3):
            page = browser.new_page(viewport={"width": 1280, "height": 900})
            t0 = time.perf_counter()
            page.goto(url, wait_until="load")
            page.wait_for_function(f"{VIEW}?._fullLayout", polling=20)
            loads.append(time.perf_counter() - t0)
            page.close()
        page = browser.new_page(viewport={"width": 1280, "height": 900})
        page.goto(url, wait_until="load")
        page.wait_for_function(f"{VIEW}?._fullLayout")
        page.locator("#animation-view").scroll_into_view_if_needed()
        step = page.evaluate(f"{VIEW}._transitionData._frames.length > 1 ? "
                             f"Number({VIEW}.layout.sliders[0].steps[1].label) : 0")
        for t in args.times:
            k = round(t / step)
            page.evaluate(f"Plotly.animate({VIEW}, ['{k}'], {{mode: 'immediate', "
                          "frame: {duration: 0, redraw: true}, transition: {duration: 0}})")
            page.wait_for_timeout(800)
            path = args.out / f"animation_t{t:.2f}s.png"
            page.locator("#animation-view").screenshot(path=str(path))
            shots.append(str(path))
        page.evaluate(f"Plotly.animate({VIEW}, ['0'], {{mode: 'immediate', "
                      "frame: {duration: 0, redraw: true}, transition: {duration: 0}})")
        page.evaluate(f"""window.__frames = 0;
            {VIEW}.on('plotly_animatingframe', () => window.__frames++);
            Plotly.animate({VIEW}, null, {{frame: {{duration: {1000 * step}, redraw: true}},
                                           transition: {{duration: 0}}, fromcurrent: true}});""")
        page.wait_for_timeout(1000 * PLAY_S)
        played = page.evaluate("window.__frames")
        browser.close()
    row = {"report": str(args.report), "size_MB": args.report.stat().st_size / 1e6,
           "load_s": statistics.median(loads), "loads_s": loads,
           "frames_per_s_at_1x": played / PLAY_S, "frames_per_s_wanted": 1 / step,
           "screenshots": shots}
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "animation_view.json").write_text(json.dumps(row, indent=1) + "\n")
    print(json.dumps(row, indent=1))


if __name__ == "__main__":
    main()
