"""The picture of a recording's default view, as a reviewer first sees it (run on demand; docs/images).

    python tools/recording_picture.py RUN.rrd PICTURE.png [--wait 40] [--size 1600x1000]

Serves the recording to Rerun's web viewer (the ``rerun`` CLI of the installed rerun-sdk), opens that in headless
Chromium with software WebGL, lets it load for ``--wait`` seconds and saves a screenshot: the layout the recording's
blueprint opens on, the time cursor at its end. Chromium is driven over its DevTools pipe (file descriptors 3 and 4,
messages ended by NUL), so nothing beyond the standard library is needed here; Chromium itself is a system tool, not
a project dependency (Debian: ``apt-get install chromium``): without it the script says so and exits 2. A picture
taken before the viewer has loaded shows "Loading Application Bundle": raise --wait.
"""

from __future__ import annotations

import argparse
import base64
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path


def _port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _answering(url: str, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        try:
            urllib.request.urlopen(url, timeout=2)
            return
        except OSError:
            time.sleep(0.3)
    raise RuntimeError(f"the viewer's server does not answer at {url}")


class DevToolsPipe:
    """Chromium's DevTools protocol over its pipe: one JSON command per NUL-ended message, answers by id."""

    def __init__(self, send_fd: int, receive_fd: int):
        self._out, self._in = os.fdopen(send_fd, "wb", buffering=0), os.fdopen(receive_fd, "rb", buffering=0)
        self._next, self._pending = 0, b""

    def call(self, method: str, session: str | None = None, **params) -> dict:
        self._next += 1
        message = {"id": self._next, "method": method, "params": params}
        if session:
            message["sessionId"] = session
        self._out.write(json.dumps(message).encode() + b"\0")
        while True:
            reply = json.loads(self._message())
            if reply.get("id") == self._next:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply.get("result", {})

    def _message(self) -> bytes:
        while b"\0" not in self._pending:
            chunk = self._in.read(1 << 16)
            if not chunk:
                raise RuntimeError("Chromium closed its DevTools pipe")
            self._pending += chunk
        message, self._pending = self._pending.split(b"\0", 1)
        return message


def _stop(process: subprocess.Popen) -> None:
    """End a process started in its own session, with its children (the `rerun` CLI is a wrapper)."""
    try:
        os.killpg(process.pid, signal.SIGTERM)
        process.wait(timeout=10)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass


def picture(rrd: Path, png: Path, wait: float = 40.0, size: tuple[int, int] = (1600, 1000)) -> Path:
    """Save the default view of recording ``rrd`` as ``png`` after ``wait`` seconds of loading."""
    rerun = shutil.which("rerun")
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if not rerun or not chromium:
        missing = "the `rerun` CLI (the project's environment)" if not rerun else "Chromium (apt-get install chromium)"
        raise FileNotFoundError(f"a picture of the viewer needs {missing}")
    web, grpc = _port(), _port()
    profile = tempfile.mkdtemp(prefix="skive-picture-")
    server = subprocess.Popen(
        [rerun, "--serve-web", "--web-viewer-port", str(web), "--port", str(grpc), str(rrd)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    browser = None
    commands, replies = os.pipe(), os.pipe()  # ours -> Chromium's fd 3, Chromium's fd 4 -> ours
    try:
        _answering(f"http://127.0.0.1:{web}", 30)
        url = f"http://127.0.0.1:{web}?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A{grpc}%2Fproxy"

        def pipes() -> None:  # in the child: the DevTools pipe on the descriptors Chromium reads and writes
            os.dup2(commands[0], 3)
            os.dup2(replies[1], 4)

        args = ["--headless=new", "--no-sandbox", "--use-gl=angle", "--use-angle=swiftshader"]
        args += ["--enable-unsafe-swiftshader", f"--window-size={size[0]},{size[1]}", "--remote-debugging-pipe"]
        browser = subprocess.Popen(
            [chromium, *args, f"--user-data-dir={profile}", url],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
            preexec_fn=pipes,
            pass_fds=(3, 4),  # kept open after pipes() made them (every other descriptor is closed)
        )
        os.close(commands[0])
        os.close(replies[1])
        devtools = DevToolsPipe(commands[1], replies[0])
        pages = [t for t in devtools.call("Target.getTargets")["targetInfos"] if t["type"] == "page"]
        session = devtools.call("Target.attachToTarget", targetId=pages[0]["targetId"], flatten=True)["sessionId"]
        time.sleep(wait)
        shot = devtools.call("Page.captureScreenshot", session=session, format="png")
        png.write_bytes(base64.b64decode(shot["data"]))
        return png
    finally:
        for process in (browser, server):
            if process is not None:
                _stop(process)
        shutil.rmtree(profile, ignore_errors=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rrd", type=Path)
    ap.add_argument("png", type=Path)
    ap.add_argument("--wait", type=float, default=40.0, help="seconds to let the viewer load the recording")
    ap.add_argument("--size", default="1600x1000", help="the window, WIDTHxHEIGHT pixels")
    a = ap.parse_args()
    try:
        width, height = (int(v) for v in a.size.lower().split("x"))
    except ValueError:
        print(f"--size {a.size!r}: give WIDTHxHEIGHT in pixels, e.g. 1600x1000", file=sys.stderr)
        return 2
    try:
        path = picture(a.rrd, a.png, a.wait, (width, height))
    except FileNotFoundError as exc:
        print(exc, file=sys.stderr)
        return 2
    print(f"saved {path} ({width}x{height}) after {a.wait:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
