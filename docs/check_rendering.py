"""Open built documentation pages in headless Chromium and check that they render with their figures.

``python3 docs/check_rendering.py docs/_build/html [--out DIR]``: for the home page and the thesis
blockage tutorial, every ``<img>`` must point at a PNG that exists in the build, the page must have
at least the figures it is expected to show, and a full-page screenshot (written to ``DIR``,
default ``docs/_build/screenshots``) must not be blank. Exit code 1 names what failed; 2 when
Chromium is not installed (Debian package ``chromium``).
"""

from __future__ import annotations

import argparse
import html.parser
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

#: page -> the least number of figures it shows
PAGES = {"index.html": 1, "tutorials/thesis-blockage.html": 2}
CHROMIUM_FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--no-first-run", "--hide-scrollbars")


class _Images(html.parser.HTMLParser):
    """The ``src`` of every ``<img>`` in the main content of a page."""

    def __init__(self):
        super().__init__()
        self.sources: list[str] = []

    def handle_starttag(self, tag, attrs):
        if tag == "img":
            self.sources.append(dict(attrs).get("src", ""))


def figures_of(page: Path) -> list[Path]:
    """The PNG files a page's ``<img>`` tags point at (the theme's logos and icons are SVG)."""
    parser = _Images()
    parser.feed(page.read_text(encoding="utf-8"))
    return [(page.parent / src).resolve() for src in parser.sources if src.endswith(".png")]


def screenshot(chromium: str, page: Path, out: Path) -> Path:
    """A 1280-pixel-wide full-page screenshot of ``page`` in a fresh browser profile."""
    with tempfile.TemporaryDirectory(prefix="genthermal-chromium-") as profile:
        subprocess.run([chromium, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", "--window-size=1280,3000",
                        "--virtual-time-budget=10000", f"--screenshot={out}", page.resolve().as_uri()],
                       check=True, capture_output=True, timeout=120)
    return out


def not_blank(png: Path) -> bool:
    """True when the screenshot has text and pictures: many distinct colours, not one background."""
    import matplotlib.image
    import numpy as np

    pixels = (matplotlib.image.imread(png)[..., :3] * 255).astype(np.uint8).reshape(-1, 3)
    return len(np.unique(pixels, axis=0)) > 200


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("html", type=Path, help="the built HTML folder (sphinx -b html output)")
    parser.add_argument("--out", type=Path, help="folder for the screenshots (default HTML/../screenshots)")
    args = parser.parse_args(argv)
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        print("check_rendering: chromium is not installed (apt-get install chromium)", file=sys.stderr)
        return 2
    out = args.out or args.html.parent / "screenshots"
    out.mkdir(parents=True, exist_ok=True)
    failures = []
    for name, least in PAGES.items():
        page = args.html / name
        if not page.is_file():
            failures.append(f"{name}: not built")
            continue
        figures = figures_of(page)
        missing = [str(f) for f in figures if not f.is_file() or f.stat().st_size < 2000]
        if len(figures) < least:
            failures.append(f"{name}: {len(figures)} figures, expected at least {least}")
        if missing:
            failures.append(f"{name}: figures missing or empty: {', '.join(missing)}")
        shot = screenshot(chromium, page, out / (name.replace("/", "_").removesuffix(".html") + ".png"))
        if not not_blank(shot):
            failures.append(f"{name}: the screenshot {shot} is blank")
        print(f"{name}: {len(figures)} figures, screenshot {shot}")
    for failure in failures:
        print(f"check_rendering: {failure}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
