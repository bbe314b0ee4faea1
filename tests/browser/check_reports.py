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
Given as alarm=URL (a daemon that will raise an alarm, e.g. the monitoring
demo's), the page is also left open at 390 px while its JSON is polled
every 0.2 s; once the JSON shows the alarm ("High: inspect"), the open page
must show it by itself within one refresh (its refresh_seconds, plus 1.5 s
to load).

Usage: python check_reports.py [--chromium PATH] [--screenshots DIR]
           KIND=REPORT.html ...      (KIND: event, period or monitoring)
           status=http://127.0.0.1:PORT/  alarm=http://127.0.0.1:PORT/
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
    "status": ["verdict", "now", "trends"],
    "alarm": ["verdict", "now", "trends"],
}

LIVE = ("status", "alarm")
ALARM = "High: inspect"

CHROMIUM_FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def wait_for_status(url, ready, timeout, every=0.5):
    """Polls a status page's JSON until `ready(status)`: the status and the
    monotonic time it was first seen."""
    import json
    import time
    import urllib.request

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            with urllib.request.urlopen(url.rstrip("/") + "/status.json", timeout=5) as r:
                status = json.load(r)
            if ready(status):
                return status, time.monotonic()
        except OSError:
            pass
        time.sleep(every)
    sys.exit(f"{url}: not there within {timeout} s")


def check_alarm_shown(page, url, tag):
    """The open page shows the alarm within one refresh of its JSON."""
    import time

    refresh = float(page.get_attribute('meta[http-equiv="refresh"]', "content"))
    status, seen = wait_for_status(url, lambda s: s.get("priority") == ALARM, timeout=300, every=0.2)
    deadline = seen + refresh + 1.5
    while time.monotonic() < deadline:
        try:
            if ALARM in page.inner_text("#verdict .priority", timeout=500):
                shown = time.monotonic() - seen
                print(f"{tag}: the alarm on the page {shown:.1f} s after its JSON (refresh {refresh:.0f} s): {status['verdict'][:90]}…")
                return []
        except Exception:  # the page is between two loads
            pass
        page.wait_for_timeout(100)
    return [f"{tag}: the JSON showed {ALARM!r} but the page did not within {refresh + 1.5:.1f} s"]


def check(browser, kind, path, screenshots):
    problems = []
    live = kind in LIVE
    url = path if live else path.resolve().as_uri()
    if live:
        wait_for_status(url, lambda s: s.get("last_update"), timeout=90)
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
        name = kind if live else path.name
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
        if not dom["figures"] and not live:
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
        if live and width == 390:
            # The browser reloads the page by itself (its refresh): within
            # a few refreshes it shows a later update than it first did.
            first = page.inner_text("#status-table")
            page.wait_for_timeout(6000)
            if page.inner_text("#status-table") == first:
                problems.append(f"{tag}: the page did not refresh to a later update within 6 s")
            if kind == "alarm":
                problems += check_alarm_shown(page, url, tag)
            if console or requests:
                problems.append(f"{tag}: after the refreshes: console {console}, requests {requests}")
        if screenshots:
            stem = kind if live else path.stem
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
            problems += check(browser, kind, name if kind in LIVE else Path(name), args.screenshots)
        browser.close()
    for problem in problems:
        print("FAIL", problem, file=sys.stderr)
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
