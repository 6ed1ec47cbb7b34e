"""Frame intervals of the report's 3-D replay while it plays, in headless Chromium (CDP).

usage: /work/py-venv/bin/python replay_fps.py REPORT.html [SECONDS]  (needs the websockets package; a measurement, not a test)
Starts chromium with SwiftShader WebGL, loads the page, selects the first run, presses Play and
collects requestAnimationFrame timestamps (window.ofmpcReplay.stamps) for SECONDS, then prints
the median, p90 and mean frame interval (ms) and the load average.
"""
import asyncio, json, os, subprocess, sys, tempfile, time, urllib.request
import websockets

async def main(page, seconds):
    prof = tempfile.mkdtemp()
    port = 9333
    p = subprocess.Popen(["chromium", "--headless", "--no-sandbox", "--use-gl=swiftshader",
        "--enable-unsafe-swiftshader", "--enable-webgl", "--ignore-gpu-blocklist",
        "--window-size=1200,900", f"--user-data-dir={prof}", f"--remote-debugging-port={port}",
        "about:blank"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        for _ in range(100):
            try:
                tabs = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/json"))
                break
            except Exception:
                time.sleep(0.2)
        ws_url = [t for t in tabs if t["type"] == "page"][0]["webSocketDebuggerUrl"]
        async with websockets.connect(ws_url, max_size=None) as ws:
            n = 0
            async def call(method, **params):
                nonlocal n
                n += 1
                await ws.send(json.dumps({"id": n, "method": method, "params": params}))
                while True:
                    m = json.loads(await ws.recv())
                    if m.get("id") == n:
                        return m
            await call("Page.enable")
            await call("Page.navigate", url="file://" + os.path.abspath(page) + "#sec-3-d-replay")
            await asyncio.sleep(4)
            r = await call("Runtime.evaluate", expression="document.getElementById('replay').getAttribute('data-ready')", returnByValue=True)
            print("replay ready:", r["result"]["result"].get("value"))
            r = await call("Runtime.evaluate", expression="(function(){var S=window.ofmpcReplay,t0=performance.now();for(var i=0;i<300;i++){S.setFrame(i*6);}var gl=document.getElementById('replay-canvas').getContext('webgl');var px=new Uint8Array(4);gl.readPixels(0,0,1,1,gl.RGBA,gl.UNSIGNED_BYTE,px);return (performance.now()-t0)/300;})()", returnByValue=True)
            print(f"draw() incl. GL submission, 300 frames then a readPixels sync: {r['result']['result']['value']:.2f} ms per frame")
            await call("Runtime.evaluate", expression="document.getElementById('replay').scrollIntoView(); window.ofmpcReplay.stamps.length = 0; window.ofmpcReplay.play(true); 1")
            await asyncio.sleep(seconds)
            r = await call("Runtime.evaluate", expression="JSON.stringify({s: window.ofmpcReplay.stamps, frames: window.ofmpcReplay.frames, draws: window.ofmpcReplay.draws})", returnByValue=True)
            d = json.loads(r["result"]["result"]["value"])
            s = d["s"]
            iv = sorted(b - a for a, b in zip(s, s[1:]))
            if not iv:
                print("no frames"); return
            med = iv[len(iv) // 2]; p90 = iv[int(len(iv) * 0.9)]
            print(f"frames {len(s)} in {seconds} s; interval median {med:.2f} ms, p90 {p90:.2f} ms, mean {sum(iv)/len(iv):.2f} ms; fps (median) {1000/med:.1f}; replay frames {d['frames']}")
            print("load:", open("/proc/loadavg").read().strip())
    finally:
        p.kill()

asyncio.run(main(sys.argv[1], float(sys.argv[2]) if len(sys.argv) > 2 else 5))
