"""Another site's page, in a real browser (Playwright driving Debian's chromium), cannot use the local servers
(issue 26 item 8). The browser resolves ``evil.test`` to 127.0.0.1 (``--host-resolver-rules``), as an
attacker's DNS would: its page, on a port of its own, posts a model to the editor's ``/api/upload`` (the
request a cross-site form sends) and opens ``mpeg4fa serve``'s WebSocket; then the browser is pointed at
``http://evil.test:EDITOR_PORT/`` itself (DNS rebinding). The editor's model stays as it was, the socket
never opens, the rebound page is refused; the editor's own page is checked by the other browser tests."""
from __future__ import annotations

import functools
import threading
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer

from e2e.browser import ARGS, CHROMIUM, require_browser

sync_api = require_browser()

from mpeg4fa.serve.app import create_app as serve_app  # noqa: E402
from mpeg4fa.web.app import create_app as editor_app  # noqa: E402
from serve.live_server import face_for_tests, running  # noqa: E402

EVIL = """<!doctype html><meta charset="utf-8"><title>a page elsewhere</title><script type="module">
const form = new FormData();
form.append("file", new Blob(["v 0 0 0\\nv 1 0 0\\nv 0 1 0\\nf 1 2 3\\n"]), "mine.obj");
const out = {};
try { await fetch("EDITOR/api/upload", {method: "POST", body: form, mode: "no-cors"}); out.upload = "sent"; }
catch (e) { out.upload = "failed: " + e; }
out.socket = await new Promise(done => {
  const ws = new WebSocket("SERVE_WS");
  ws.onopen = () => done("open"); ws.onerror = () => done("refused");
});
window.results = out;
</script>"""


class _Quiet(SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


def test_a_page_elsewhere_cannot_upload_open_the_socket_or_rebind(tmp_path, procedural_face):
    editor = editor_app(out_dir=tmp_path / "out", head=procedural_face)
    before = editor.state.session.mesh  # None: nothing loaded yet; an accepted upload would load one
    live = serve_app(face_for_tests(), engine="estimate")
    site = tmp_path / "site"
    site.mkdir()
    with running(editor) as editor_base, running(live) as serve_base:
        editor_port = editor_base.rsplit(":", 1)[1]
        (site / "evil.html").write_text(EVIL.replace("EDITOR", editor_base)  # what a cross-site request targets
                                        .replace("SERVE_WS", serve_base.replace("http://", "ws://") + "/ws"))
        server = ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(_Quiet, directory=str(site)))
        threading.Thread(target=server.serve_forever, daemon=True).start()
        try:
            with sync_api.sync_playwright() as p:
                browser = p.chromium.launch(executable_path=CHROMIUM,
                                            args=ARGS + ["--host-resolver-rules=MAP evil.test 127.0.0.1"])
                page = browser.new_page()
                page.goto(f"http://evil.test:{server.server_address[1]}/evil.html")
                page.wait_for_function("window.results !== undefined", timeout=15_000)
                results = page.evaluate("window.results")
                rebound = page.goto(f"http://evil.test:{editor_port}/")  # the attacker's name, now 127.0.0.1
                status, text = rebound.status, page.content()
                api = page.goto(f"http://evil.test:{editor_port}/api/model")
                browser.close()
        finally:
            server.shutdown()
    assert results["upload"] == "sent", results  # the browser sent it (no-cors): the server must refuse it
    assert editor.state.session.mesh is before, "a page elsewhere replaced the editor's model"
    assert results["socket"] == "refused", results
    assert live.state.live.connections == 0 and not live.state.live.utterances
    assert status == 403 and "not this server's loopback address" in text, (status, text[:300])
    assert api.status == 403
