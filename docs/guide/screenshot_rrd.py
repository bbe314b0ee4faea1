#!/usr/bin/env python3
"""A picture of a Rerun recording as the viewer draws it, on a machine
without a display: the viewer runs headless (`rerun --headless`) and its own
MCP control server (`rerun viewer-mcp`, stdio JSON-RPC) selects a tab and
takes the screenshot.

    .venv/bin/python docs/guide/screenshot_rrd.py out/overpass/results.rrd \
        /tmp/overpass-mesh.png --maximize "Deck: patches" --hide-panels

Needs rerun-sdk==0.36.3 in the venv (the README's Python set-up). The
viewer listens on --port (default 9877) of loopback only.
"""

import argparse
import base64
import json
import os
import subprocess
import sys
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rrd")
    ap.add_argument("png")
    ap.add_argument("--tab", action="append", default=[],
                    help="click the tab whose label contains this (repeatable, in order)")
    ap.add_argument("--maximize", help="maximise the view whose title contains this")
    ap.add_argument("--hide-panels", action="store_true", help="hide the blueprint, selection and time panels")
    ap.add_argument("--drag", action="append", default=[], metavar="X0,Y0,X1,Y1",
                    help="drag in the window (orbits a 3-D view's eye; repeatable)")
    ap.add_argument("--scroll", action="append", default=[], metavar="X,Y,DY",
                    help="scroll at X,Y by DY points (zooms a 3-D view; repeatable)")
    ap.add_argument("--size", default="1400x800")
    ap.add_argument("--port", type=int, default=9877)
    ap.add_argument("--settle", type=float, default=4.0, help="seconds to wait after loading and after each click")
    args = ap.parse_args()
    rerun = os.path.join(os.path.dirname(sys.executable), "rerun")
    width, height = (int(v) for v in args.size.split("x"))
    viewer = subprocess.Popen(
        [rerun, "--headless", "--bind", "127.0.0.1", "--port", str(args.port), args.rrd],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )
    mcp = subprocess.Popen([rerun, "viewer-mcp"], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                           stderr=subprocess.DEVNULL, text=True)
    ids = iter(range(1, 1 << 30))

    def call(method, params):
        mcp.stdin.write(json.dumps({"jsonrpc": "2.0", "id": next(ids), "method": method, "params": params}) + "\n")
        mcp.stdin.flush()
        reply = json.loads(mcp.stdout.readline())
        if "error" in reply or reply.get("result", {}).get("isError"):
            raise RuntimeError(f"{method} {params}: {reply}")
        return reply["result"]

    def tool(name, **arguments):
        return call("tools/call", {"name": name, "arguments": arguments})

    def nodes(**query):
        return json.loads(tool("query_tree", **query)["content"][0]["text"])["nodes"]

    try:
        call("initialize", {"protocolVersion": "2024-11-05", "capabilities": {},
                            "clientInfo": {"name": "splinewatch-docs", "version": "1"}})
        mcp.stdin.write(json.dumps({"jsonrpc": "2.0", "method": "notifications/initialized"}) + "\n")
        mcp.stdin.flush()
        endpoint = f"http://127.0.0.1:{args.port}"
        for attempt in range(60):
            try:
                tool("connect", endpoint=endpoint)
                break
            except RuntimeError:
                if attempt == 59:
                    raise
                time.sleep(0.5)
        tool("resize", width=width, height=height)
        time.sleep(args.settle)
        for tab in args.tab:
            tool("click", label_contains=tab)
            time.sleep(args.settle)
        if args.maximize:
            # The view's pane, then the "Maximize view" button in its title bar.
            panes = [n for n in nodes(label_contains=args.maximize) if n["role"] == "Pane"]
            if not panes:
                raise RuntimeError(f"no view titled {args.maximize!r}")
            pane = panes[0]["bounds"]
            buttons = [b for b in nodes(label_contains="Maximize view")
                       if pane["x"] <= b["bounds"]["x"] <= pane["x"] + pane["w"] + 20
                       and pane["y"] - 30 <= b["bounds"]["y"] <= pane["y"]]
            if not buttons:
                raise RuntimeError(f"no maximise button over the view {args.maximize!r}")
            tool("click", id=buttons[0]["id"])
            time.sleep(args.settle)
        if args.hide_panels:
            for panel in ("Blueprint panel toggle", "Selection panel toggle", "Time panel toggle"):
                tool("click", label_contains=panel)
            time.sleep(args.settle)
        for drag in args.drag:
            x0, y0, x1, y1 = (float(v) for v in drag.split(","))
            tool("drag", start={"pos": {"x": x0, "y": y0}}, end={"pos": {"x": x1, "y": y1}})
            time.sleep(args.settle)
        for scroll in args.scroll:
            x, y, dy = (float(v) for v in scroll.split(","))
            tool("scroll", pos={"x": x, "y": y}, delta={"x": 0.0, "y": dy})
            time.sleep(args.settle)
        # The pointer off the view: no hover tooltip in the picture.
        tool("hover", pos={"x": 1.0, "y": float(height - 1)})
        time.sleep(1.0)
        shot = tool("screenshot")
        images = [c for c in shot["content"] if c.get("type") == "image"]
        if not images:
            raise RuntimeError(f"no image in the screenshot reply: {shot}")
        with open(args.png, "wb") as f:
            f.write(base64.b64decode(images[0]["data"]))
        print(f"{args.png}: {width}x{height}")
    finally:
        mcp.kill()
        viewer.kill()


if __name__ == "__main__":
    main()
