"""Render an spflow HTML report in headless Chromium and save a full-height PNG screenshot (issue 11's browser check).

    python scripts/screenshot_report.py out/workflow/report.html out/workflow/report_screenshot.png [--height 12000]

Needs a Chromium binary (Debian: ``apt-get install chromium``; found as ``chromium``, ``chromium-browser`` or
``google-chrome`` on PATH, or ``--chromium PATH``). The page is self-contained (figures inlined), so no server is
needed; the screenshot shows exactly what a browser shows, figures included.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
from pathlib import Path


def chromium_binary(explicit: str | None) -> str:
    for name in ([explicit] if explicit else ["chromium", "chromium-browser", "google-chrome"]):
        found = shutil.which(name)
        if found:
            return found
    sys.exit("no Chromium found: install it (Debian: apt-get install chromium) or pass --chromium PATH")


def screenshot(report: Path, png: Path, *, width: int, height: int, chromium: str) -> Path:
    subprocess.run([chromium, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                    f"--window-size={width},{height}", f"--screenshot={png.resolve()}", report.resolve().as_uri()],
                   check=True, capture_output=True, timeout=120)
    return png


def main(argv=None) -> Path:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("report", type=Path)
    parser.add_argument("png", type=Path)
    parser.add_argument("--width", type=int, default=1300)
    parser.add_argument("--height", type=int, default=12000)
    parser.add_argument("--chromium")
    args = parser.parse_args(argv)
    if not args.report.is_file():
        sys.exit(f"no report at {args.report}: run `spflow run workflow` (or `spflow report PIPELINE`) first")
    return screenshot(args.report, args.png, width=args.width, height=args.height,
                      chromium=chromium_binary(args.chromium))


if __name__ == "__main__":
    print(main())
