"""A headless Chromium with WebGPU (SwiftShader) driven over WebDriver by chromedriver, serving the built page
(target/web): what scripts/web/test_page.py and scripts/web/bench.py stand on. Standard library only.

The page reports itself in `#status` ("scene=… strategy=… spp=N mean=X …", or "error: …") and publishes where its
controls are in `#ui-map` ("name x y" per line, CSS pixels from the canvas's top left): a test reads the one and
clicks the other with real pointer events, as a user would.
"""
import base64
import json
import os
import re
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request

# Chromium's WebGPU on SwiftShader, headless (issue 45); no network, no first-run chores.
FLAGS = ["--headless=new", "--no-sandbox", "--enable-unsafe-webgpu", "--enable-features=Vulkan",
         "--use-vulkan=swiftshader", "--use-angle=swiftshader", "--disable-gpu-sandbox", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync", "--disable-quic",
         "--window-size=1280,800"]


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def fields(status):
    """`key=value` pairs of a status line."""
    return dict(re.findall(r"(\w+)=(\S+)", status))


class Page:
    """The page in a browser session: open, read the status, click controls, drop files, download."""

    def __init__(self, web, chromium="/usr/bin/chromium", chromedriver="/usr/bin/chromedriver"):
        for need in (chromium, chromedriver):
            if not os.path.exists(need):
                sys.exit(f"FAIL: {need} is missing (apt-get install chromium chromium-driver)")
        if not os.path.exists(os.path.join(web, "mislab_web_bg.wasm")):
            sys.exit(f"FAIL: {web} has no built page (scripts/web/build.sh)")
        self.downloads = tempfile.mkdtemp(prefix="mislab-web-downloads-")
        self.web_port, driver_port = free_port(), free_port()
        self.server = subprocess.Popen(
            [sys.executable, "-m", "http.server", str(self.web_port), "-d", web, "--bind", "127.0.0.1"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self.driver = subprocess.Popen([chromedriver, f"--port={driver_port}"], stdout=subprocess.DEVNULL,
                                       stderr=subprocess.DEVNULL)
        base = f"http://127.0.0.1:{driver_port}"
        for _ in range(100):
            try:
                self._call("GET", f"{base}/status")
                break
            except OSError:
                time.sleep(0.2)
        options = {"binary": chromium, "args": FLAGS + [f"--user-data-dir={self.downloads}-profile"],
                   "prefs": {"download.default_directory": self.downloads, "download.prompt_for_download": False}}
        caps = {"capabilities": {"alwaysMatch": {"browserName": "chrome", "goog:loggingPrefs": {"browser": "ALL"},
                                                 "goog:chromeOptions": options}}}
        self.session = f"{base}/session/" + self._call("POST", f"{base}/session", caps)["sessionId"]
        self._call("POST", f"{self.session}/goog/cdp/execute", {"cmd": "Browser.setDownloadBehavior", "params": {
            "behavior": "allow", "downloadPath": self.downloads}})

    def _call(self, method, url, body=None):
        data = None if body is None else json.dumps(body).encode()
        req = urllib.request.Request(url, data=data, method=method, headers={"Content-Type": "application/json"})
        with urllib.request.urlopen(req, timeout=300) as r:
            return json.loads(r.read())["value"]

    def js(self, script, *args):
        return self._call("POST", f"{self.session}/execute/sync", {"script": script, "args": list(args)})

    def open(self, query):
        self._call("POST", f"{self.session}/url", {"url": f"http://127.0.0.1:{self.web_port}/?{query}"})

    def status(self):
        return self.js("return document.getElementById('status').textContent")

    def wait(self, what, done, timeout):
        """Waits until `done(fields)` holds; fails (never skips) on an error line or after `timeout` s."""
        t0, status = time.time(), ""
        while time.time() - t0 < timeout:
            status = self.status()
            if status.startswith(("error", "mislab panicked")):
                self.console()
                raise SystemExit(f"FAIL: {what}: the page says {status!r} (no WebGPU adapter?)")
            f = fields(status)
            if "spp" in f and done(f):
                return f, time.time() - t0
            time.sleep(0.5)
        self.console()
        raise SystemExit(f"FAIL: {what}: not done after {timeout:.0f} s; the page says {status!r}")

    def controls(self):
        text = self.js("return document.getElementById('ui-map').textContent") or ""
        out = {}
        for line in text.splitlines():
            name, x, y = line.rsplit(" ", 2)
            out[name] = (float(x), float(y))
        return out

    def click(self, name):
        """A real click (pointer events at the control's place on the canvas)."""
        controls = self.controls()
        if name not in controls:
            raise SystemExit(f"FAIL: the panel has no control {name!r} (it has: {', '.join(sorted(controls))})")
        left, top = self.js("const r = document.getElementById('mislab').getBoundingClientRect(); "
                            "return [r.left, r.top];")
        x, y = controls[name]
        actions = {"actions": [{"type": "pointer", "id": "mouse", "parameters": {"pointerType": "mouse"}, "actions": [
            {"type": "pointerMove", "duration": 0, "origin": "viewport", "x": int(left + x), "y": int(top + y)},
            {"type": "pointerDown", "button": 0}, {"type": "pause", "duration": 50},
            {"type": "pointerUp", "button": 0}]}]}
        self._call("POST", f"{self.session}/actions", actions)
        self._call("DELETE", f"{self.session}/actions")

    def drop(self, paths):
        """Drops files on the canvas as a user drags them from a file manager (a DataTransfer of Files)."""
        files = [[os.path.basename(p), base64.b64encode(open(p, "rb").read()).decode()] for p in paths]
        self.js("""
            const dt = new DataTransfer();
            for (const [name, b64] of arguments[0]) {
                const bytes = Uint8Array.from(atob(b64), c => c.charCodeAt(0));
                dt.items.add(new File([bytes], name));
            }
            const canvas = document.getElementById('mislab');
            canvas.dispatchEvent(new DragEvent('dragover', {dataTransfer: dt, bubbles: true, cancelable: true}));
            canvas.dispatchEvent(new DragEvent('drop', {dataTransfer: dt, bubbles: true, cancelable: true}));
        """, files)

    def downloaded(self, name, timeout=60):
        path = os.path.join(self.downloads, name)
        t0 = time.time()
        while time.time() - t0 < timeout:
            if os.path.exists(path) and not os.path.exists(path + ".crdownload") and os.path.getsize(path) > 0:
                return path
            time.sleep(0.3)
        raise SystemExit(f"FAIL: the download {name} never arrived (have: {os.listdir(self.downloads)})")

    def screenshot(self, path):
        with open(path, "wb") as f:
            f.write(base64.b64decode(self._call("GET", f"{self.session}/screenshot")))

    def console(self):
        for entry in self._call("POST", f"{self.session}/se/log", {"type": "browser"}):
            if entry.get("level") in ("SEVERE", "WARNING") and "favicon" not in entry.get("message", ""):
                print(f"  browser console: {entry.get('message', '')[:2000]}")

    def close(self):
        try:
            self._call("DELETE", self.session)
        finally:
            self.driver.terminate()
            self.server.terminate()
