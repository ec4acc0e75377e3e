"""The local web server of ``skyscatter view``: the viewer page, its script and the GLSL library from the package,
and the textures of one export folder, on 127.0.0.1 only (standard library :mod:`http.server`).

Routes: ``/`` (the page), ``/viewer/<file>`` (the page's script and style), ``/glsl/atmosphere.glsl``,
``/luts/<file>`` (the manifest and the texture files it lists, nothing else of the folder). Nothing is fetched
from the network: the page loads only these.
"""

from __future__ import annotations

import threading
from functools import partial
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from pathlib import Path
from urllib.parse import unquote, urlsplit

from ..errors import InvalidParameterError
from .export import MANIFEST_NAME
from .loader import read_manifest

__all__ = ["ViewerServer", "serve"]

_TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
          ".css": "text/css; charset=utf-8", ".glsl": "text/plain; charset=utf-8",
          ".json": "application/json"}
_PACKAGE_FILES = {"/viewer/viewer.js", "/viewer/style.css", "/glsl/atmosphere.glsl"}


def _package_bytes(route: str) -> bytes:
    rel = "viewer/index.html" if route == "/" else route.lstrip("/")
    return resources.files(__package__).joinpath(rel).read_bytes()


class _Handler(BaseHTTPRequestHandler):
    server_version = "skyscatter-view"

    def __init__(self, *args, luts: Path, quiet: bool, **kwargs) -> None:
        self.luts = luts
        self.quiet = quiet
        super().__init__(*args, **kwargs)

    def log_message(self, format: str, *args) -> None:  # noqa: A002 - the base class's name
        if not self.quiet:
            super().log_message(format, *args)

    def _send(self, body: bytes, content_type: str, head_only: bool = False) -> None:
        self.send_response(HTTPStatus.OK)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        if not head_only:
            self.wfile.write(body)

    def _lut_file(self, name: str) -> Path | None:
        """The export folder's manifest or a file it lists; None otherwise (no other file is served)."""
        if name == MANIFEST_NAME:
            return self.luts / MANIFEST_NAME
        try:
            manifest = read_manifest(self.luts)
        except Exception:  # a broken manifest: the page reports it when it reads the manifest itself
            return None
        listed = {f["file"] for t in manifest.get("textures", {}).values() for f in t.get("files", {}).values()}
        return self.luts / name if name in listed else None

    def do_GET(self, head_only: bool = False) -> None:  # noqa: N802 - http.server's name
        route = unquote(urlsplit(self.path).path)
        if route in ("/", "/index.html") or route in _PACKAGE_FILES:
            route = "/" if route == "/index.html" else route
            self._send(_package_bytes(route), _TYPES[Path(route).suffix or ".html"], head_only)
            return
        if route.startswith("/luts/") and "/" not in route[6:]:
            path = self._lut_file(route[6:])
            if path is not None and path.is_file():
                self._send(path.read_bytes(), _TYPES.get(path.suffix, "application/octet-stream"), head_only)
                return
        self.send_error(HTTPStatus.NOT_FOUND, "not part of the viewer")

    def do_HEAD(self) -> None:  # noqa: N802
        self.do_GET(head_only=True)


class ViewerServer:
    """The viewer's HTTP server on 127.0.0.1 (``port`` 0: any free port), serving ``luts`` (an export folder)."""

    def __init__(self, luts: str | Path, *, port: int = 0, quiet: bool = True) -> None:
        if not (isinstance(port, int) and 0 <= port <= 65535):
            raise InvalidParameterError(f"port must be a whole number in 0..65535; got {port!r}")
        self.luts = Path(luts)
        handler = partial(_Handler, luts=self.luts, quiet=quiet)
        try:
            self.httpd = ThreadingHTTPServer(("127.0.0.1", port), handler)
        except OSError as exc:
            raise InvalidParameterError(f"cannot listen on 127.0.0.1:{port}: {exc.strerror or exc} (choose "
                                        "another --port, or 0 for any free one)") from None
        self.httpd.daemon_threads = True
        self._thread: threading.Thread | None = None

    @property
    def url(self) -> str:
        host, port = self.httpd.server_address[:2]
        host = host.decode() if isinstance(host, bytes) else host
        return f"http://{host}:{port}/"

    def start(self) -> ViewerServer:
        """Serve in a background thread; returns self."""
        self._thread = threading.Thread(target=self.httpd.serve_forever, daemon=True)
        self._thread.start()
        return self

    def serve_forever(self) -> None:
        self.httpd.serve_forever()

    def close(self) -> None:
        if self._thread is not None:
            self.httpd.shutdown()
        self.httpd.server_close()

    def __enter__(self) -> ViewerServer:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.close()


def serve(luts: str | Path, *, port: int = 0, quiet: bool = True) -> ViewerServer:
    """Start a :class:`ViewerServer` in the background and return it (``close()`` it when done)."""
    return ViewerServer(luts, port=port, quiet=quiet).start()
