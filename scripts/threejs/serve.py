#!/usr/bin/env python3
"""shoot.sh's HTTP server, on 127.0.0.1 and a free port.

    serve.py HARNESS_DIR SCENE_DIR STATE_DIR

GET /scene/PATH serves SCENE_DIR/PATH (the .glb and its lightmaps), any other GET serves HARNESS_DIR (view.html,
view.js, node_modules/three). POST /result stores the page's JSON report as STATE_DIR/result.json (written
whole, then renamed). The port is written to STATE_DIR/port once listening; every path asked for is appended
to STATE_DIR/requests (so shoot.sh can tell whether the browser ever reached the page).
"""

import functools
import http.server
import os
import sys
import urllib.parse


class Handler(http.server.SimpleHTTPRequestHandler):
    extensions_map = {
        **http.server.SimpleHTTPRequestHandler.extensions_map,
        ".js": "text/javascript",
        ".mjs": "text/javascript",
        ".glb": "model/gltf-binary",
        ".exr": "image/x-exr",
    }

    def __init__(self, *args, harness, scene, state, **kwargs):
        self.harness, self.scene, self.state = harness, scene, state
        super().__init__(*args, directory=harness, **kwargs)

    def translate_path(self, path):
        clean = urllib.parse.unquote(urllib.parse.urlsplit(path).path)
        if clean.startswith("/scene/"):
            root, rest = self.scene, clean[len("/scene/") :]
        else:
            root, rest = self.harness, clean.lstrip("/")
        parts = [p for p in rest.split("/") if p not in ("", ".", "..")]
        return os.path.join(root, *parts)

    def end_headers(self):
        self.send_header("Cache-Control", "no-store")
        super().end_headers()

    def do_GET(self):
        with open(os.path.join(self.state, "requests"), "a") as f:
            f.write(self.path + "\n")
        super().do_GET()

    def do_POST(self):
        if urllib.parse.urlsplit(self.path).path != "/result":
            self.send_error(404)
            return
        body = self.rfile.read(int(self.headers.get("Content-Length", "0")))
        partial = os.path.join(self.state, "result.json.partial")
        with open(partial, "wb") as f:
            f.write(body)
        os.replace(partial, os.path.join(self.state, "result.json"))
        self.send_response(204)
        self.end_headers()

    def log_message(self, format, *args):
        pass


def main():
    harness, scene, state = (os.path.abspath(a) for a in sys.argv[1:4])
    handler = functools.partial(Handler, harness=harness, scene=scene, state=state)
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    partial = os.path.join(state, "port.partial")
    with open(partial, "w") as f:
        f.write(f"{server.server_address[1]}\n")
    os.replace(partial, os.path.join(state, "port"))
    server.serve_forever()


if __name__ == "__main__":
    main()
