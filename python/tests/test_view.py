"""`frepray view` in a real browser: headless Chromium (Debian's chromium and
chromium-driver, which scripts/setup.sh installs), driven over the WebDriver protocol.
The page shows the image the server holds, pixel for pixel; a click fills the
inspector; saving the scene re-renders; a broken scene shows its located error.

Where the browser cannot start, these tests fail: they do not skip."""

import base64
import json
import os
import shutil
import signal
import socket
import struct
import subprocess
import time
import urllib.error
import urllib.request
import zlib

import pytest

from conftest import ROOT

SCENE = """
camera = { eye = [0, -4, 1.5], target = [0, 0, 0.3], resolution = [48, 36] }
render = { integrator = "direct", estimator = "optimal-direct", spp = 8 }
materials.white = { type = "diffuse", reflectance = 0.7 }
objects = [
  { solid = "z + 1", material = "white" },
  { solid = "sphere([0, 0, 0], 1)", material = "white" },
]
lights = [{ type = "sphere", center = [1, -2, 3], radius = 0.4, power = POWER }]
"""


def png_pixels(data: bytes):
    """(width, height, rows of RGB tuples) of an 8-bit RGB or RGBA PNG."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, width = 8, b"", None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, color = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and color in (2, 6), (depth, color)
            channels = 3 if color == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw, stride = zlib.decompress(idat), width * channels
    rows, prev, i = [], bytearray(stride), 0
    for _ in range(height):
        f, line = raw[i], bytearray(raw[i + 1:i + 1 + stride])
        i += 1 + stride
        for x in range(stride):
            a = line[x - channels] if x >= channels else 0
            b, c = prev[x], prev[x - channels] if x >= channels else 0
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + b) & 255
            elif f == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[x] = (line[x] + pred) & 255
        rows.append([tuple(line[k:k + 3]) for k in range(0, stride, channels)])
        prev = line
    return width, height, rows


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def call(method, url, body=None):
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(url, data=data, method=method,
                                 headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(req, timeout=60) as r:
        return json.loads(r.read())


class Browser:
    """A headless Chromium session over chromedriver's WebDriver endpoint."""

    def __init__(self, tmp):
        chromium, driver = shutil.which("chromium"), shutil.which("chromedriver")
        assert chromium and driver, ("the browser tests need Debian's chromium and "
                                     "chromium-driver (bash scripts/setup.sh installs them)")
        self.port = free_port()
        self.driver = subprocess.Popen([driver, f"--port={self.port}"],
                                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self.base = f"http://127.0.0.1:{self.port}"
        for _ in range(200):
            try:
                if call("GET", self.base + "/status")["value"]["ready"]:
                    break
            except (urllib.error.URLError, ConnectionError):
                pass
            time.sleep(0.05)
        args = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                "--no-first-run", "--disable-background-networking",
                "--disable-component-update", "--disable-sync", "--force-device-scale-factor=1",
                f"--user-data-dir={tmp / 'chromium-profile'}", "--window-size=1200,900"]
        caps = {"capabilities": {"alwaysMatch": {"browserName": "chrome", "goog:chromeOptions": {
            "binary": chromium, "args": args}}}}
        self.session = call("POST", self.base + "/session", caps)["value"]["sessionId"]
        self.url = f"{self.base}/session/{self.session}"

    def go(self, url):
        call("POST", self.url + "/url", {"url": url})

    def js(self, script, *args):
        return call("POST", self.url + "/execute/sync", {"script": script, "args": list(args)})[
            "value"]

    def wait(self, script, what, timeout=60):
        end = time.time() + timeout
        while time.time() < end:
            v = self.js(script)
            if v:
                return v
            time.sleep(0.1)
        raise AssertionError(f"waiting for {what}: {self.js('return window.frepray')}")

    def element(self, css):
        v = call("POST", self.url + "/element", {"using": "css selector", "value": css})["value"]
        return next(iter(v.values()))

    def screenshot(self, element):
        shot = call("GET", f"{self.url}/element/{element}/screenshot")["value"]
        return base64.b64decode(shot)

    def click(self, element, x, y):
        """A real click at (x, y) from the element's top-left corner (WebDriver offsets
        count from its centre)."""
        rect = call("GET", f"{self.url}/element/{element}/rect")["value"]
        dx, dy = int(x - rect["width"] / 2), int(y - rect["height"] / 2)
        actions = {"actions": [{"type": "pointer", "id": "mouse", "parameters": {
            "pointerType": "mouse"}, "actions": [
            {"type": "pointerMove", "duration": 0, "origin": {
                "element-6066-11e4-a52e-4f735466cecf": element}, "x": dx, "y": dy},
            {"type": "pointerDown", "button": 0}, {"type": "pointerUp", "button": 0}]}]}
        call("POST", self.url + "/actions", actions)

    def close(self):
        try:
            call("DELETE", self.url)
        finally:
            self.driver.terminate()
            self.driver.wait(10)


@pytest.fixture
def viewer(cli, tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE.replace("POWER", "100"))
    proc = subprocess.Popen([str(cli), "view", str(scene)], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    url = proc.stdout.readline().strip()
    assert url.startswith("http://127.0.0.1:"), (url, proc.stderr.read())
    yield scene, url
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    assert "stopped" in err, err


def server_png(url, **params):
    base, token = url.split("/?token=")
    query = "&".join(f"{k}={v}" for k, v in dict(params, token=token).items())
    with urllib.request.urlopen(f"{base}/image.png?{query}", timeout=30) as r:
        return r.read()


def test_the_page_shows_the_render_inspects_and_follows_edits(viewer, tmp_path):
    scene, url = viewer
    browser = Browser(tmp_path)
    try:
        browser.go(url)
        done = ("const f = window.frepray; return f && f.shown && f.shown.spp === 8 && "
                "document.getElementById('img').complete && f.shown")
        shown = browser.wait(done, "the last pass on screen")
        img = browser.element("#img")
        # The screenshot of the image is the server's PNG, pixel for pixel.
        w, h, page = png_pixels(browser.screenshot(img))
        sw, sh, held = png_pixels(server_png(url, view="color", exposure=0, tonemap="clamp"))
        assert (w, h) == (sw, sh) == (48, 36)
        worst = max(abs(a - b) for r1, r2 in zip(page, held) for p, q in zip(r1, r2)
                    for a, b in zip(p, q))
        assert worst <= 2, worst
        # Zoomed 4×, a click on pixel (30, 20) fills the inspector with its record.
        browser.js("const z = document.getElementById('zoom'); z.value = '4'; "
                   "z.dispatchEvent(new Event('change'));")
        browser.wait("return document.getElementById('img').getBoundingClientRect().width "
                     "=== 192", "the zoom")
        _, _, page = png_pixels(browser.screenshot(img))
        browser.click(img, 4 * 30 + 2, 4 * 20 + 2)
        p = browser.wait("return window.frepray.inspected", "the inspector")
        assert (p["x"], p["y"], p["samples"]) == (30, 20, 8), p
        text = browser.js("return document.getElementById('inspector').innerText")
        assert "pixel (30, 20)" in text and "α light-power:1" in text, text
        # Saving a brighter scene re-renders it; the page follows.
        time.sleep(0.5)
        scene.write_text(SCENE.replace("POWER", "400"))
        g = shown["generation"]
        browser.wait(f"const f = window.frepray; return f.shown && f.shown.generation > {g} "
                     "&& f.shown.spp === 8", "the re-render")
        _, _, brighter = png_pixels(browser.screenshot(img))
        total = lambda rows: sum(sum(p) for r in rows for p in r)  # noqa: E731
        assert total(brighter) > 1.3 * total(page)
        # A broken scene: the located error, and the last image stays.
        time.sleep(0.3)
        scene.write_text(SCENE.replace("POWER", "400").replace("reflectance = 0.7",
                                                                "reflectance = oops"))
        err = browser.wait("const e = document.getElementById('error'); "
                           "return e.style.display === 'block' && e.innerText", "the error")
        assert "scene.toml:4:" in err, err
        _, _, kept = png_pixels(browser.screenshot(img))
        assert kept == brighter
    finally:
        browser.close()


def test_the_viewer_from_python(tmp_path):
    # The same server from Python: a page at 127.0.0.1 with a token, the render's status
    # as JSON, refused without the token, and closed on leaving the block.
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE.replace("POWER", "100"))
    import frepray

    with frepray.Viewer(scene) as v:
        assert v.url.startswith("http://127.0.0.1:") and "token=" in v.url
        base, token = v.url.split("/?token=")
        for _ in range(600):
            with urllib.request.urlopen(f"{base}/status?token={token}", timeout=10) as r:
                status = json.loads(r.read())
            if status["spp"] == 8:
                break
            time.sleep(0.05)
        assert status["spp"] == 8 and status["width"] == 48, status
        with pytest.raises(urllib.error.HTTPError) as e:
            urllib.request.urlopen(f"{base}/status", timeout=10)
        assert e.value.code == 403
    with pytest.raises(urllib.error.URLError):
        urllib.request.urlopen(f"{base}/status?token={token}", timeout=5)
