"""The owner's reports in a real browser (headless Chromium, Playwright).

Each HTML report given is opened from disk, as from an e-mail attachment,
at a desktop width and at a phone's 390 px, and checked:

- no console error, no page error, and no network request at all (the
  report must not fetch anything: every request is counted and refused);
- the verdict, its priority, every figure (an inline SVG with drawn marks)
  and every table (with rows) are in the DOM, and the sections the report
  kind must have;
- at 390 px nothing overflows the page horizontally.

With --screenshots DIR, each report's top at 390 px and its full page at
1000 px are saved there as PNG (the guide's images).

A running daemon's status page is given as status=URL: once its JSON
shows an update, the page is checked the same way (it has no figure), and
at 390 px it must show a later update by itself (its refresh) within 6 s.

Usage: python check_reports.py [--chromium PATH] [--screenshots DIR]
           KIND=REPORT.html ...      (KIND: event, period or monitoring)
           status=http://127.0.0.1:PORT/
"""

import argparse
import sys
from pathlib import Path

from playwright.sync_api import sync_playwright

REQUIRED = {
    "event": ["verdict", "shaking", "features", "forecast", "modes", "skipped", "provenance"],
    "period": ["verdict", "trends", "alarms", "provenance"],
    "monitoring": ["verdict", "state", "trends", "alarms", "health", "provenance"],
    # A running daemon's status page (`[web]`), by its URL.
    "status": ["verdict", "now"],
}

CHROMIUM_FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def wait_for_update(url, timeout=90.0):
    """Polls a status page's JSON until the daemon has written an update."""
    import json
    import time
    import urllib.request

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            with urllib.request.urlopen(url.rstrip("/") + "/status.json", timeout=5) as r:
                status = json.load(r)
            if status.get("last_update"):
                return status
        except OSError:
            pass
        time.sleep(0.5)
    sys.exit(f"{url}: no update within {timeout} s")


def check(browser, kind, path, screenshots):
    problems = []
    url = path if kind == "status" else path.resolve().as_uri()
    if kind == "status":
        wait_for_update(url)
    for width in (1000, 390):
        page = browser.new_page(viewport={"width": width, "height": 800})
        console, requests = [], []
        page.on("console", lambda m: console.append(m.text) if m.type in ("error", "warning") else None)
        page.on("pageerror", lambda e: console.append(str(e)))

        def refuse(route):
            if route.request.url != url:
                requests.append(route.request.url)
                route.abort()
            else:
                route.continue_()

        page.route("**/*", refuse)
        page.goto(url, wait_until="load")
        dom = page.evaluate(
            """() => ({
                verdict: (document.querySelector('#verdict-text') || {}).textContent || '',
                priority: (document.querySelector('#verdict .priority') || {}).textContent || '',
                sections: [...document.querySelectorAll('section[id]')].map(s => s.id),
                figures: [...document.querySelectorAll('figure')].map(f => ({
                    id: f.id,
                    svg: !!f.querySelector('svg'),
                    marks: f.querySelectorAll('svg circle, svg rect, svg polyline, svg path, svg polygon, svg line').length,
                    caption: (f.querySelector('figcaption') || {}).textContent || '',
                    width: f.getBoundingClientRect().width,
                })),
                tables: [...document.querySelectorAll('table')].map(t => ({
                    id: t.id, rows: t.querySelectorAll('tbody tr').length })),
                scrollWidth: document.documentElement.scrollWidth,
                clientWidth: document.documentElement.clientWidth,
                images: document.images.length,
                scripts: document.scripts.length,
            })"""
        )
        name = "status" if kind == "status" else path.name
        tag = f"{name} at {width} px"
        if console:
            problems.append(f"{tag}: console: {console}")
        if requests:
            problems.append(f"{tag}: network requests: {requests}")
        if len(dom["verdict"].strip()) < 20 or not dom["priority"].strip():
            problems.append(f"{tag}: no verdict or priority ({dom['verdict']!r}, {dom['priority']!r})")
        for section in REQUIRED[kind]:
            if section != "verdict" and section not in dom["sections"]:
                problems.append(f"{tag}: section {section!r} missing (has {dom['sections']})")
        if not dom["figures"] and kind != "status":
            problems.append(f"{tag}: no figure")
        for f in dom["figures"]:
            if not f["svg"] or f["marks"] < 5 or not f["caption"].strip():
                problems.append(f"{tag}: figure {f['id']} empty: {f}")
            if f["width"] > width:
                problems.append(f"{tag}: figure {f['id']} wider than the page: {f['width']}")
        if not dom["tables"] or any(t["rows"] == 0 for t in dom["tables"]):
            problems.append(f"{tag}: a table without rows: {dom['tables']}")
        if dom["scrollWidth"] > dom["clientWidth"]:
            problems.append(f"{tag}: overflows horizontally ({dom['scrollWidth']} > {dom['clientWidth']} px)")
        if dom["scripts"]:
            problems.append(f"{tag}: {dom['scripts']} scripts")
        if kind == "status" and width == 390:
            # The browser reloads the page by itself (its refresh): within
            # a few refreshes it shows a later update than it first did.
            first = page.inner_text("#status-table")
            page.wait_for_timeout(6000)
            if page.inner_text("#status-table") == first:
                problems.append(f"{tag}: the page did not refresh to a later update within 6 s")
            if console or requests:
                problems.append(f"{tag}: after the refreshes: console {console}, requests {requests}")
        if screenshots:
            stem = "status" if kind == "status" else path.stem
            if width == 390:
                page.screenshot(path=str(screenshots / f"{stem}-phone.png"))
            else:
                page.screenshot(path=str(screenshots / f"{stem}.png"), full_page=True)
        print(
            f"{tag}: {dom['priority']}: {dom['verdict'][:90]}… "
            f"{len(dom['figures'])} figures, {len(dom['tables'])} tables, width {dom['scrollWidth']} px"
        )
        page.close()
    return problems


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--chromium", default="/usr/bin/chromium")
    parser.add_argument("--screenshots", type=Path)
    parser.add_argument("reports", nargs="+")
    args = parser.parse_args()
    if not Path(args.chromium).exists():
        sys.exit(f"no Chromium at {args.chromium}: install Debian's chromium (apt-get install chromium)")
    if args.screenshots:
        args.screenshots.mkdir(parents=True, exist_ok=True)
    problems = []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=args.chromium, args=CHROMIUM_FLAGS)
        for item in args.reports:
            kind, _, name = item.partition("=")
            if kind not in REQUIRED:
                sys.exit(f"{item}: give KIND=PATH, KIND one of {sorted(REQUIRED)}")
            problems += check(browser, kind, name if kind == "status" else Path(name), args.screenshots)
        browser.close()
    for problem in problems:
        print("FAIL", problem, file=sys.stderr)
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
