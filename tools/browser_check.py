"""Load an HTML page in headless Chromium; fail on console errors, uncaught exceptions or a blank page.

Usage::

    python tools/browser_check.py PAGE.html [--screenshot OUT.png] [--width 1280] [--height 2000]

Chromium is driven over the DevTools protocol on a pipe (``--remote-debugging-pipe``: commands on file
descriptor 3, replies on 4, each a JSON message ended by a NUL byte), not by scraping its log: with
``--enable-logging=stderr`` this Chromium prints every console message as ``INFO:CONSOLE`` whatever its
level, so ``console.error`` cannot be told from ``console.log`` there.  Over the protocol the check collects

* ``Runtime.exceptionThrown`` — an uncaught exception (``throw new Error(...)``, a syntax error);
* ``Runtime.consoleAPICalled`` of type ``error`` or ``assert`` — ``console.error(...)``, a failed
  ``console.assert``;
* ``Log.entryAdded`` of level ``error`` — what the browser itself reports, e.g. an image or script that
  failed to load;

then takes a screenshot of the first ``width × height`` pixels (``Page.captureScreenshot``) and calls the page
blank when one colour covers more than ``--blank-fraction`` of it (default 0.995).

Exit status: 0 the page passed; 1 console errors, exceptions or a blank page (each printed to stderr);
2 Chromium is missing or did not answer (the message says how to install it: ``apt-get install chromium``).
"""

from __future__ import annotations

import argparse
import base64
import fcntl
import json
import os
import select
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

INSTALL = "install it with `apt-get update && apt-get install -y chromium` (Debian package chromium)"


#: Run in the child: fd argv[1] → 3, fd argv[2] → 4 (both inheritable), then exec argv[3:].
_TRAMPOLINE = ("import os, sys; os.dup2(int(sys.argv[1]), 3); os.dup2(int(sys.argv[2]), 4); "
               "os.execv(sys.argv[3], sys.argv[3:])")


class BrowserError(RuntimeError):
    """Chromium is missing, did not start, or stopped answering."""


class _Pipe:
    """The DevTools protocol over Chromium's ``--remote-debugging-pipe``."""

    def __init__(self, proc: subprocess.Popen, write_fd: int, read_fd: int, timeout: float) -> None:
        self.proc, self.wfd, self.rfd, self.timeout = proc, write_fd, read_fd, timeout
        self.buf, self.events, self.next_id = b"", [], 0

    def _read_message(self, deadline: float) -> dict | None:
        while b"\0" not in self.buf:
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            ready, _, _ = select.select([self.rfd], [], [], left)
            if not ready:
                return None
            chunk = os.read(self.rfd, 1 << 16)
            if not chunk:
                raise BrowserError("Chromium closed the DevTools pipe (it crashed or exited)")
            self.buf += chunk
        msg, self.buf = self.buf.split(b"\0", 1)
        return json.loads(msg)

    def send(self, method: str, params: dict | None = None, session: str | None = None) -> dict:
        self.next_id += 1
        msg = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self.wfd, json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + self.timeout
        while True:
            reply = self._read_message(deadline)
            if reply is None:
                raise BrowserError(f"Chromium did not answer {method} within {self.timeout:g} s")
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise BrowserError(f"{method} failed: {reply['error']}")
                return reply.get("result", {})
            self.events.append(reply)

    def wait_for(self, method: str, seconds: float) -> bool:
        """Collect events for up to ``seconds``; True as soon as ``method`` arrives."""
        if any(e.get("method") == method for e in self.events):
            return True
        deadline = time.monotonic() + seconds
        while True:
            ev = self._read_message(deadline)
            if ev is None:
                return False
            self.events.append(ev)
            if ev.get("method") == method:
                return True

    def drain(self, seconds: float) -> None:
        """Collect the events of the next ``seconds``."""
        deadline = time.monotonic() + seconds
        while (ev := self._read_message(deadline)) is not None:
            self.events.append(ev)


def find_chromium(explicit: str | None = None) -> str:
    """Path of the Chromium binary (``explicit``, ``$CHROMIUM``, or ``chromium`` on PATH)."""
    for name in (explicit, os.environ.get("CHROMIUM"), "chromium", "chromium-browser"):
        if name and (path := shutil.which(name)):
            return path
    raise BrowserError(f"Chromium not found on PATH; {INSTALL}")


def _problems(events: list[dict]) -> list[str]:
    """Console errors, uncaught exceptions and browser error log entries among the protocol events."""
    out = []
    for ev in events:
        method, p = ev.get("method"), ev.get("params", {})
        if method == "Runtime.exceptionThrown":
            d = p.get("exceptionDetails", {})
            text = d.get("exception", {}).get("description") or d.get("text", "exception")
            out.append(f"uncaught exception (line {d.get('lineNumber', 0) + 1}): {text.splitlines()[0]}")
        elif method == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
            args = " ".join(str(a.get("value", a.get("description", ""))) for a in p.get("args", []))
            out.append(f"console.{p['type']}: {args}")
        elif method == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
            e = p["entry"]
            out.append(f"browser log error ({e.get('source')}): {e.get('text')} {e.get('url', '')}".rstrip())
    return out


def blank_fraction(png: bytes) -> float:
    """Fraction of the screenshot's pixels that have its most common colour."""
    import io

    import matplotlib.image as mpimg
    import numpy as np

    img = mpimg.imread(io.BytesIO(png), format="png")
    px = np.round(np.asarray(img)[..., :3].reshape(-1, 3) * 255).astype(np.int64)
    codes = (px[:, 0] << 16) | (px[:, 1] << 8) | px[:, 2]
    return float(np.bincount(np.unique(codes, return_inverse=True)[1]).max() / codes.size)


def _high_fd(fd: int) -> int:
    """A copy of ``fd`` numbered 100 or more (close-on-exec); ``fd`` is closed."""
    high = fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 100)
    os.close(fd)
    return high


def check_page(page: str | Path, screenshot: str | Path | None = None, width: int = 1280, height: int = 2000,
               blank: float = 0.995, timeout: float = 60.0, chromium: str | None = None) -> list[str]:
    """Load ``page`` in headless Chromium; the list of problems (empty when the page passed).

    Raises BrowserError when Chromium is missing or does not answer.
    """
    page = Path(page).resolve()
    if not page.is_file():
        raise BrowserError(f"no such page: {page}")
    binary = find_chromium(chromium)
    to_chrome_r, to_chrome_w = os.pipe()
    from_chrome_r, from_chrome_w = os.pipe()
    to_chrome_r, from_chrome_w = _high_fd(to_chrome_r), _high_fd(from_chrome_w)  # so dup2 to 3, 4 is safe
    with tempfile.TemporaryDirectory(prefix="browser-check-") as profile:
        args = [binary, "--headless", "--no-sandbox", "--disable-gpu", "--remote-debugging-pipe",
                "--no-first-run", "--no-default-browser-check", "--disable-extensions",
                f"--user-data-dir={profile}", f"--window-size={width},{height}", "about:blank"]

        # The child reads commands on fd 3 and writes replies on fd 4: a tiny Python trampoline moves the pipe
        # ends there and execs Chromium (a preexec_fn cannot: subprocess closes other fds after it runs; dash
        # refuses fd numbers above 9 in redirections).
        wrapper = [sys.executable, "-c", _TRAMPOLINE, str(to_chrome_r), str(from_chrome_w), *args]
        try:
            proc = subprocess.Popen(wrapper, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                    stderr=subprocess.DEVNULL, pass_fds=(to_chrome_r, from_chrome_w))
        except OSError as exc:
            raise BrowserError(f"cannot start {binary}: {exc}") from exc
        os.close(to_chrome_r)
        os.close(from_chrome_w)
        cdp = _Pipe(proc, to_chrome_w, from_chrome_r, timeout)
        try:
            target = cdp.send("Target.createTarget", {"url": "about:blank"})["targetId"]
            session = cdp.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
            for method in ("Runtime.enable", "Log.enable", "Page.enable"):
                cdp.send(method, session=session)
            cdp.send("Emulation.setDeviceMetricsOverride",
                     {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False}, session=session)
            cdp.events.clear()
            cdp.send("Page.navigate", {"url": page.as_uri()}, session=session)
            if not cdp.wait_for("Page.loadEventFired", timeout):
                raise BrowserError(f"{page} did not finish loading within {timeout:g} s")
            cdp.drain(0.3)  # errors raised just after the load event (timers, late scripts)
            shot = cdp.send("Page.captureScreenshot", {"format": "png"}, session=session)
            png = base64.b64decode(shot["data"])
            cdp.drain(0.1)
            problems = _problems(cdp.events)
            try:
                cdp.send("Browser.close")
            except BrowserError:
                pass
        finally:
            os.close(to_chrome_w)
            os.close(from_chrome_r)
            try:
                proc.wait(10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
    if screenshot is not None:
        out = Path(screenshot)
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = out.with_name(f".{out.name}.tmp")
        tmp.write_bytes(png)
        os.replace(tmp, out)
    frac = blank_fraction(png)
    if frac > blank:
        problems.append(f"blank page: {frac:.2%} of the {width}x{height} screenshot is one colour")
    return problems


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("page", help="the HTML file")
    ap.add_argument("--screenshot", help="write the screenshot (PNG) here")
    ap.add_argument("--width", type=int, default=1280)
    ap.add_argument("--height", type=int, default=2000)
    ap.add_argument("--blank-fraction", type=float, default=0.995,
                    help="blank when one colour covers more than this fraction of the screenshot")
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds to wait for Chromium and the page")
    ap.add_argument("--chromium", help="the Chromium binary (default $CHROMIUM or chromium on PATH)")
    a = ap.parse_args(argv)
    try:
        problems = check_page(a.page, a.screenshot, a.width, a.height, a.blank_fraction, a.timeout, a.chromium)
    except BrowserError as exc:
        print(f"browser_check: {exc}", file=sys.stderr)
        return 2
    for p in problems:
        print(f"browser_check: {a.page}: {p}", file=sys.stderr)
    if problems:
        return 1
    print(f"browser_check: {a.page}: no console errors, page not blank")
    return 0


if __name__ == "__main__":
    sys.exit(main())
