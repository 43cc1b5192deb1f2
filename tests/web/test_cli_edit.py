"""``mpeg4fa edit`` starts the app on 127.0.0.1 only (the server run replaced: no socket in the tests)."""
import pytest
import trimesh

from mpeg4fa.cli import local_server


def test_edit_serves_on_localhost_only(cli, tmp_path, monkeypatch):
    seen = {}
    monkeypatch.setattr(local_server, "run_until_stopped", lambda app, **kw: seen.update(kw, app=app))
    ball = tmp_path / "ball.obj"
    trimesh.creation.icosphere(1).export(ball)
    code, out, err = cli("edit", ball, "--port", "8999", "--out", tmp_path, "--no-browser")
    assert code == 0, err
    assert seen["host"] == "127.0.0.1" and seen["port"] == 8999
    assert seen["app"].state.session.mesh.source == "ball.obj"
    assert "http://127.0.0.1:8999/" in out


def test_edit_refuses_a_bad_port(cli):
    with pytest.raises(SystemExit):
        cli("edit", "--port", "0")
