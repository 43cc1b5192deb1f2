"""``say`` as a library function: text -> stream -> decoded -> rendered, kept files beside, nothing left on failure."""
from __future__ import annotations

import json

import pytest

from mpeg4fa.atomic import PARTIAL_MARK
from mpeg4fa.render import RenderError
from mpeg4fa.render.video import probe_media
from mpeg4fa.say import kept_paths, say


def test_the_readme_names_import_from_the_speech_package():
    from mpeg4fa.speech import Encoded, MarkupError, TTSError, encode_text, make_engine, parse_markup
    from mpeg4fa.speech import say as speech_say
    assert speech_say is say and callable(encode_text) and callable(make_engine) and callable(parse_markup)
    assert issubclass(MarkupError, Exception) and issubclass(TTSError, Exception) and Encoded.__name__ == "Encoded"


def test_kept_paths_sit_beside_the_output(tmp_path):
    kept = kept_paths(tmp_path / "my.talk.mp4")
    assert [p.name for p in kept.values()] == ["my.talk.fba", "my.talk.wav", "my.talk.timings.json"]
    assert kept_paths(tmp_path / "frames")["stream"] == tmp_path / "frames.fba"


def test_say_renders_what_a_receiver_decodes_and_keeps_its_files(procedural_face, tmp_path):
    out = tmp_path / "hi.mp4"
    said = say("(joy, 30, 0.3) Hi there.", out, face=procedural_face, width=64, height=64, samples=0, keep=True)
    info = probe_media(out)
    assert info.n_frames == said.result.n_frames >= 10 and len(said.stream) >= 10
    assert said.kept["stream"].read_bytes() == said.data
    assert said.kept["audio"].stat().st_size > 44
    assert json.loads(said.kept["timings"].read_text(encoding="utf-8"))[0]["viseme"]
    assert not [p for p in tmp_path.iterdir() if PARTIAL_MARK in p.name]


def test_a_failed_render_leaves_nothing(procedural_face, tmp_path, monkeypatch):
    from mpeg4fa.render.renderer import Renderer

    calls = []
    real = Renderer.render

    def failing(self, *args, **kwargs):
        calls.append(1)
        if len(calls) > 3:
            raise RenderError("the GPU went away", where="renderer")
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Renderer, "render", failing)
    for out in (tmp_path / "hi.mp4", tmp_path / "frames"):
        calls.clear()
        with pytest.raises(RenderError, match="went away"):
            say("Hello there, my old friend.", out, face=procedural_face, width=64, height=64, samples=0,
                keep=True)
        assert not out.exists()
        assert not any(p.exists() for p in kept_paths(out).values())
    assert list(tmp_path.iterdir()) == []
