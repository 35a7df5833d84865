#!/usr/bin/env python3
"""Screenshot of a report's comparison viewer in headless Chromium (the README's picture).

    tools/viewer_screenshot.py REPORT.html OUT.png [--keys 6] [--region penumbra] [--view image]

Loads the report from disk, waits until the viewer has decoded its images, selects the region
(its button), presses the keys (as the browser's own key events), moves the pointer over the
canvas (the pixel probe) and writes a PNG of the viewer's section. Drives Chromium through the
DevTools protocol on --remote-debugging-pipe (file descriptors 3 and 4, NUL-separated JSON), so
it needs nothing beyond Python's standard library and /usr/bin/chromium.
"""
import argparse
import base64
import json
import os
import subprocess
import sys
import tempfile
import time


class Browser:
    def __init__(self, profile):
        to_child_read, self.to_child = os.pipe()
        self.from_child, from_child_write = os.pipe()

        def fds():
            # Copies first: either pipe end may itself be descriptor 3 or 4.
            read_copy, write_copy = os.dup(to_child_read), os.dup(from_child_write)
            os.dup2(read_copy, 3)
            os.dup2(write_copy, 4)

        self.process = subprocess.Popen(
            ["/usr/bin/chromium", "--headless=new", "--no-sandbox", "--disable-gpu",
             "--no-first-run", "--remote-debugging-pipe", "--user-data-dir=" + profile,
             "about:blank"],
            preexec_fn=fds, pass_fds=(3, 4),
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(to_child_read)
        os.close(from_child_write)
        self.buffer = b""
        self.next_id = 1
        self.session = None

    def call(self, method, params=None, browser_level=False):
        message = {"id": self.next_id, "method": method, "params": params or {}}
        if self.session and not browser_level:
            message["sessionId"] = self.session
        self.next_id += 1
        os.write(self.to_child, json.dumps(message).encode() + b"\0")
        while True:
            while b"\0" not in self.buffer:
                chunk = os.read(self.from_child, 1 << 16)
                if not chunk:
                    raise RuntimeError("chromium exited")
                self.buffer += chunk
            text, self.buffer = self.buffer.split(b"\0", 1)
            reply = json.loads(text)
            if reply.get("id") == message["id"]:
                if "error" in reply:
                    raise RuntimeError(method + ": " + json.dumps(reply["error"]))
                return reply.get("result", {})

    def eval(self, expression):
        result = self.call("Runtime.evaluate", {"expression": expression, "returnByValue": True,
                                                "awaitPromise": True})
        if "exceptionDetails" in result:
            raise RuntimeError(json.dumps(result["exceptionDetails"]))
        return result["result"].get("value")

    def close(self):
        try:
            self.call("Browser.close", browser_level=True)
        except Exception:
            pass
        try:
            self.process.wait(5)
        except subprocess.TimeoutExpired:
            self.process.kill()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("report")
    parser.add_argument("output")
    parser.add_argument("--keys", default="", help="keys to press, e.g. 6e")
    parser.add_argument("--region", default="", help="region to select")
    parser.add_argument("--width", type=int, default=1300)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as profile:
        browser = Browser(profile)
        try:
            target = browser.call("Target.createTarget", {"url": "about:blank"})["targetId"]
            browser.session = browser.call("Target.attachToTarget",
                                           {"targetId": target, "flatten": True})["sessionId"]
            browser.call("Emulation.setDeviceMetricsOverride",
                         {"width": args.width, "height": 1000, "deviceScaleFactor": 1,
                          "mobile": False})
            browser.call("Page.navigate",
                         {"url": "file://" + os.path.abspath(args.report)})
            deadline = time.time() + 60
            while browser.eval("(function(){var v=document.getElementById('viewer');"
                               "return !!v && v.hasAttribute('data-ready');})()") is not True:
                if time.time() > deadline:
                    sys.exit("the viewer did not become ready within 60 s")
                time.sleep(0.1)
            if args.region:
                browser.eval("document.querySelector('#viewer .pv-regions button[data-region=\"%s\"]')"
                             ".click()" % args.region)
            for key in args.keys:
                browser.call("Input.dispatchKeyEvent",
                             {"type": "keyDown", "key": key, "text": key})
                browser.call("Input.dispatchKeyEvent", {"type": "keyUp", "key": key})
            box = browser.eval("(function(){var v=document.getElementById('viewer');"
                               "v.scrollIntoView();var c=v.querySelector('.pv-canvas')"
                               ".getBoundingClientRect(),r=v.getBoundingClientRect();"
                               "return [c.left,c.top,c.width,c.height,r.left+scrollX,"
                               "r.top+scrollY,r.width,r.height];})()")
            browser.call("Input.dispatchMouseEvent",
                         {"type": "mouseMoved", "x": box[0] + box[2] * 0.52,
                          "y": box[1] + box[3] * 0.4})
            shot = browser.call("Page.captureScreenshot",
                                {"format": "png", "captureBeyondViewport": True,
                                 "clip": {"x": box[4], "y": box[5], "width": box[6],
                                          "height": box[7], "scale": 1}})
            with open(args.output, "wb") as out:
                out.write(base64.b64decode(shot["data"]))
        finally:
            browser.close()
    print("wrote", args.output)


if __name__ == "__main__":
    main()
