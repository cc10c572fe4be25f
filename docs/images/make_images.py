"""Make the README's pictures: Rerun's web viewer with a validation run's ``run.rrd`` open, one
figure of the report of the same run, and its ``report.html`` in a browser.

    python docs/images/make_images.py

runs ``tumble validate`` on the default scene into a temporary directory, serves ``run.rrd``
with ``rerun --web-viewer`` on the loopback interface, opens it in headless Chromium (Debian's
``chromium`` package; no network, a new empty profile), saves the screenshot as
``docs/images/viewer.png``, copies ``tracking.png`` of the report as
``docs/images/tracking.png`` and saves the top of ``report.html`` in Chromium as
``docs/images/report.png`` (:func:`report_screenshot`), all reduced below :data:`MAX_BYTES`.

:func:`viewer_screenshot` drives Chromium over its DevTools protocol on a pipe (standard library
only); ``tests/cross/test_viewer.py`` uses it to check that a recording opens in its designed layout.
"""

from __future__ import annotations

import base64
import contextlib
import io
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.parse
from collections.abc import Iterator
from pathlib import Path

HERE = Path(__file__).resolve().parent
WINDOW = (1600, 1000)  # px: the browser window the viewer fills
RENDER_WAIT_S = 35.0
"""How long the viewer gets to load the file and draw it on the CPU (software rasteriser)."""
MAX_BYTES = 300_000
CHROMIUM_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-dev-shm-usage",
)


def chromium() -> str | None:
    """The Chromium executable, or None."""
    return shutil.which("chromium") or shutil.which("chromium-browser")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextlib.contextmanager
def web_viewer(rrd: Path) -> Iterator[str]:
    """``with web_viewer(path) as url:`` Rerun's web viewer serving ``rrd`` on the loopback
    interface; ``url`` opens it. The server is stopped when the block ends."""
    http, grpc = _free_port(), _free_port()
    cmd = [sys.executable, "-m", "rerun", "--web-viewer", "--bind", "127.0.0.1"]
    cmd += ["--web-viewer-port", str(http), "--port", str(grpc), str(rrd)]
    # Its own process group: ``python -m rerun`` starts the viewer binary as a child, which must
    # end with it (terminating the Python launcher alone left the server running, busy).
    proc = subprocess.Popen(
        cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
    )
    try:
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            with contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", http), 1):
                break
            time.sleep(0.2)
        proxy = urllib.parse.quote(f"rerun+http://127.0.0.1:{grpc}/proxy", safe="")
        yield f"http://127.0.0.1:{http}/?url={proxy}"
    finally:
        _stop_group(proc)


def _stop_group(proc: subprocess.Popen) -> None:
    """End ``proc`` and every process of its group: SIGTERM, then SIGKILL after 10 s."""
    for sig, wait_s in ((signal.SIGTERM, 10.0), (signal.SIGKILL, 10.0)):
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, sig)
        try:
            proc.wait(timeout=wait_s)
        except subprocess.TimeoutExpired:
            continue
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)  # the group's other members, should any remain
        return


class _DevTools:
    """Chromium's DevTools protocol over ``--remote-debugging-pipe`` (fds 3 and 4)."""

    def __init__(self, exe: str, profile: Path, window: tuple[int, int]):
        to_chrome, self._w = os.pipe()
        self._r, from_chrome = os.pipe()

        def fds() -> None:  # in the child: its fd 3 reads our commands, fd 4 writes replies
            a, b = os.dup(to_chrome), os.dup(from_chrome)
            os.dup2(a, 3)
            os.dup2(b, 4)

        args = [exe, *CHROMIUM_FLAGS, f"--user-data-dir={profile}"]
        args += [f"--window-size={window[0]},{window[1]}", "--remote-debugging-pipe"]
        self.proc = subprocess.Popen(
            [*args, "about:blank"],
            preexec_fn=fds,
            close_fds=False,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        os.close(to_chrome)
        os.close(from_chrome)
        self._buf, self._id, self.session = b"", 0, None

    def call(self, method: str, params: dict | None = None, timeout: float = 60.0) -> dict:
        self._id += 1
        msg = {"id": self._id, "method": method, "params": params or {}}
        if self.session:
            msg["sessionId"] = self.session
        os.write(self._w, json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            while b"\0" in self._buf:
                raw, self._buf = self._buf.split(b"\0", 1)
                reply = json.loads(raw)
                if reply.get("id") == self._id:
                    if "error" in reply:
                        raise RuntimeError(f"{method}: {reply['error']}")
                    return reply["result"]
            import select

            if select.select([self._r], [], [], 1.0)[0]:
                chunk = os.read(self._r, 1 << 20)
                if not chunk:
                    break
                self._buf += chunk
        raise TimeoutError(f"Chromium did not answer {method}")

    def close(self) -> None:
        self.proc.terminate()
        try:
            self.proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.proc.kill()
        os.close(self._w)
        os.close(self._r)


def viewer_screenshot(
    rrd: Path, out: Path, wait_s: float = RENDER_WAIT_S, window: tuple[int, int] = WINDOW
) -> Path:
    """Open ``rrd`` in Rerun's web viewer in headless Chromium (a new empty profile, no
    network) and save what it shows after ``wait_s`` seconds as the PNG ``out``."""
    exe = chromium()
    if exe is None:
        raise RuntimeError("Chromium is not installed (Debian: apt-get install chromium)")
    with tempfile.TemporaryDirectory() as profile, web_viewer(rrd) as url:
        tools = _DevTools(exe, Path(profile), window)
        try:
            target = tools.call("Target.createTarget", {"url": "about:blank"})["targetId"]
            tools.session = tools.call(
                "Target.attachToTarget", {"targetId": target, "flatten": True}
            )["sessionId"]
            w, h = window
            tools.call(
                "Emulation.setDeviceMetricsOverride",
                {"width": w, "height": h, "deviceScaleFactor": 1, "mobile": False},
            )
            tools.call("Page.navigate", {"url": url})
            time.sleep(wait_s)
            png = base64.b64decode(tools.call("Page.captureScreenshot", {"format": "png"})["data"])
        finally:
            tools.close()
    out.write_bytes(png)
    return out


def shrink_png(src: Path, dst: Path, max_bytes: int = MAX_BYTES) -> Path:
    """Copy the PNG ``src`` to ``dst``, scaled down (and its colours quantised) until it is
    under ``max_bytes``."""
    from PIL import Image

    img = Image.open(src).convert("RGB")
    scale = 1.0
    while True:
        size = (round(img.width * scale), round(img.height * scale))
        small = img.resize(size, Image.LANCZOS).quantize(colors=128, method=Image.MEDIANCUT)
        buf = io.BytesIO()
        small.save(buf, format="PNG", optimize=True)
        if buf.tell() <= max_bytes or scale < 0.3:
            dst.write_bytes(buf.getvalue())
            return dst
        scale *= 0.85


REPORT_WINDOW = (1280, 1350)
"""px: the browser window of ``report.png``: the verdict, the recording's link, the referee and
the first checks."""


def report_screenshot(html: Path, out: Path, window: tuple[int, int] = REPORT_WINDOW) -> Path:
    """Open the report ``html`` (a self-contained file: nothing to serve) in headless Chromium (a
    new empty profile, no network) and save the window as the PNG ``out``."""
    exe = chromium()
    if exe is None:
        raise RuntimeError("Chromium is not installed (Debian: apt-get install chromium)")
    with tempfile.TemporaryDirectory() as profile:
        cmd = [exe, *CHROMIUM_FLAGS, f"--user-data-dir={profile}"]
        cmd += [f"--window-size={window[0]},{window[1]}", f"--screenshot={out.resolve()}"]
        subprocess.run([*cmd, html.resolve().as_uri()], check=True, capture_output=True, cwd=profile)
    return out


PICTURE_T_END_S = 5.0
"""Horizon of the run the viewer picture shows, s: a quarter of the default scene's, so the
web viewer has the whole recording (about 1.5 MB) drawn before the screenshot."""


def main(argv: list[str] | None = None) -> int:
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--wait", type=float, default=RENDER_WAIT_S, help="seconds to let the viewer draw")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        run = Path(tmp) / "validate"
        tumble = [sys.executable, "-m", "validation.cli", "validate", "--out", str(run)]
        subprocess.run(tumble, check=True)
        short = Path(tmp) / "short"
        subprocess.run([*tumble[:-2], "--t-end", str(PICTURE_T_END_S), "--out", str(short)], check=True)
        shot = viewer_screenshot(short / "run.rrd", Path(tmp) / "viewer.png", wait_s=args.wait)
        page = report_screenshot(run / "report.html", Path(tmp) / "report.png")
        for src, name in ((shot, "viewer.png"), (run / "tracking.png", "tracking.png")):
            dst = shrink_png(src, HERE / name)
            print(f"{dst.relative_to(HERE.parents[1])}: {dst.stat().st_size} bytes")
        dst = shrink_png(page, HERE / "report.png")
        print(f"{dst.relative_to(HERE.parents[1])}: {dst.stat().st_size} bytes")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
