"""Long text is normal text (issue 26 item 2): the passes run chunk by chunk in bounded memory and give
the frames and the decoded stream the whole text gives.

References: the golden frames and bytes made by the whole-text encoder before the streaming rework
(``data/make_golden_text_frames.py``), and the whole-array timeline functions (``viseme_track``,
``expression_track``, ``idle_track``...) run over all of a text's timings at once.
"""
from __future__ import annotations

import hashlib
import io
import json
import re
import wave
from pathlib import Path

import numpy as np
import pytest

from mpeg4fa.decoded import resolve
from mpeg4fa.fba import decode, encode
from mpeg4fa.speech import MarkupError
from mpeg4fa.speech import bits as bits_module
from mpeg4fa.speech import chunks as chunks_module
from mpeg4fa.speech.chunks import CHUNK_CHARS, parse_pieces, sentence_chunks
from mpeg4fa.speech.encoder import closure_hold, encode_text, join_blocks, make_engine
from mpeg4fa.speech.markup import parse_markup
from mpeg4fa.speech.pipeline import Passes, encode_text_to, encoded_text, stream_text
from mpeg4fa.speech.timeline import (expression_fields, expression_track, frame_times, idle_track, merge_tracks,
                                     viseme_fields, viseme_track)
from mpeg4fa.speech.utterance import Utterance

DATA = Path(__file__).parent / "data"

SENTENCES = [
    "(joy, 40, 3) Good morning, and welcome to the central station.", "The next train leaves from platform four.",
    "(surprise, 35, 0.3) Oh, the bridge is closed today!", "Please take the bus from the main square instead.",
    "It stops near the old market and the museum.", "(sadness, 25, 4) We are very sorry for the trouble.",
    "Tickets are still available at the front desk.", "Remember to keep your bags with you.",
    "(joy, 0, 2.5) My grandmother grew tomatoes and beans.", "Could you send me the report by Friday?",
    "Pack my box with five dozen liquor jugs.", "(anger, 20, 5) Why was the bus late again?",
    "Because the road was blocked by a fallen tree.", "The quick brown fox jumps over the lazy dog.",
    "(neutral, 0, 0.2) Tomorrow is another day.", "She sells sea shells by the sea shore.",
    "(fear, 30, 1.5) Did you hear that noise?", "It was only the wind in the chimney.",
    "We will meet again at seven o'clock.", "(joy, 50, 2) Have a pleasant trip!",
]
TEXT = " ".join(SENTENCES)
"""20 sentences; tags whose transitions (up to 5 s) run on across sentence and chunk boundaries."""


def _grid(stream) -> np.ndarray:
    """Resolved FAP values on the frame grid (frames folded into skip counts repeated)."""
    return np.repeat(resolve(stream), stream.skip.astype(int) + 1, axis=0)


class _SameSpeech:
    """espeak-ng's timing wanders between syntheses of one text: this wrapper speaks each text once,
    so that two encodes of it are comparable."""

    def __init__(self, engine) -> None:
        self.engine, self.name, self.seen = engine, engine.name, {}
        self.speaks_ipa = getattr(engine, "speaks_ipa", False)

    def synthesize(self, text, **options):
        key = (text, repr(sorted(options.items())))
        if key not in self.seen:
            self.seen[key] = self.engine.synthesize(text, **options)
        return self.seen[key]


def test_short_texts_keep_their_frames_and_bytes():
    """One chunk: the same frames, stream and bytes as the whole-text encoder made before the passes."""
    golden = json.loads((DATA / "golden_text_frames.json").read_text(encoding="utf-8"))
    arrays = np.load(DATA / "golden_text_frames.npz")
    for text, level, idle, fps in golden["cases"]:
        key = f"{text}-{level}-{int(idle)}-{fps:g}"
        e = encode_text(golden["texts"][text], engine="estimate", level=level, idle=idle, fps=fps, seed=7)
        assert np.array_equal(e.values, arrays[key + ".values"]), key
        for field in ("fap_mask", "fap_values", "viseme", "expression"):
            assert np.array_equal(getattr(e.stream, field), arrays[key + "." + field]), (key, field)
        data = encode(e.stream, e.coding())
        assert hashlib.sha256(data).hexdigest() == golden["meta"][key]["sha256"], key


@pytest.mark.parametrize("idle, window", [(False, 4096), (True, 4096), (True, 7)])
def test_chunked_frames_equal_the_whole_text_timeline(idle, window, monkeypatch):
    """Chunk by chunk (and window by window), the frames (values and FAP 1/2 fields) are those of the
    timeline run over all the text's timings at once: tags, moves and idle motion carry across."""
    from mpeg4fa.speech import frames as frames_module

    monkeypatch.setattr(frames_module, "WINDOW", window)
    fps = 25.0
    passes = Passes(TEXT, make_engine("estimate"), fps=fps, idle=idle, seed=3, chunk_chars=150)
    chunks = list(passes)
    blocks = [c.frames for c in chunks if c.frames is not None]
    assert len(chunks) >= 5 and len(blocks) >= 4  # frames came out as the chunks went by
    blocks.append(passes.finish())
    got = join_blocks(blocks)

    timings = tuple(t for c in chunks for t in c.utterance.timings)
    cues = tuple(q for c in chunks for q in c.utterance.cues)
    spans = Utterance(chunks[0].utterance.speech, timings, cues, chunks[0].markup).spans()
    times = frame_times(passes.duration, fps)
    hold = closure_hold(fps)
    tracks = [viseme_track(spans, times, closure_hold=hold), expression_track(cues, times)]
    tracks += [idle_track(times, 3)] if idle else []
    assert np.array_equal(got.times, times)
    assert np.array_equal(got.values, np.rint(merge_tracks(*tracks)))
    vis, exp = viseme_fields(spans, times, closure_hold=hold), expression_fields(cues, times)
    assert got.visemes.select1 == vis.select1 and got.visemes.select2 == vis.select2
    assert np.array_equal(got.visemes.blend, vis.blend)
    for field in ("select1", "intensity1", "select2", "intensity2"):
        assert np.array_equal(getattr(got.expressions, field), getattr(exp, field)), field


@pytest.mark.parametrize("level", ["low", "high"])
def test_streamed_blocks_decode_as_one_stream(level, monkeypatch, tmp_path):
    """Blocks coded one by one and joined decode to what one stream of all the frames decodes to, and
    the validator reads the joined stream to its end code."""
    from mpeg4fa.cli import main

    monkeypatch.setattr(bits_module, "BLOCK_SECONDS", 2.0)
    engine = make_engine("estimate")
    text = " ".join(SENTENCES[:12])
    whole = encoded_text(text, engine, level=level, idle=True, chunk_chars=150)
    out = io.BytesIO()
    spoken = stream_text(text, out, engine=engine, level=level, idle=True, chunk_chars=150)
    streamed = decode(out.getvalue())
    assert spoken.frames == len(whole.stream) and spoken.bytes == len(out.getvalue())
    assert len(streamed.intra) >= spoken.frames // 50  # an intra frame at least every block
    assert np.allclose(_grid(streamed), _grid(decode(encode(whole.stream, whole.coding()))), rtol=0, atol=1e-9)
    path = tmp_path / "long.fba"
    path.write_bytes(out.getvalue())
    assert main(["validate", str(path)]) == 0


def test_streamed_audio_and_timings_are_the_in_memory_ones(tmp_path):
    """The WAV and the timings JSON written chunk by chunk hold what the in-memory encode holds."""
    from mpeg4fa.say import write_timings

    engine = _SameSpeech(make_engine("espeak"))
    text = " ".join(SENTENCES[:6])
    whole = encoded_text(text, engine, chunk_chars=100)
    spoken = encode_text_to(text, tmp_path / "t.fba", audio=tmp_path / "t.wav", timings=tmp_path / "t.json",
                            engine=engine, chunk_chars=100)
    assert spoken.chunks >= 3
    with wave.open(str(tmp_path / "t.wav"), "rb") as wav:
        assert wav.getframerate() == whole.speech.rate
        samples = np.frombuffer(wav.readframes(wav.getnframes()), "<i2")
    assert np.array_equal(samples, whole.speech.samples)
    write_timings(whole, tmp_path / "whole.json")
    assert (tmp_path / "t.json").read_text(encoding="utf-8") == (tmp_path / "whole.json").read_text(encoding="utf-8")
    assert spoken.seconds == pytest.approx(whole.speech.duration)


def test_progress_is_told_from_the_start_to_the_end():
    calls = []
    stream_text(TEXT, io.BytesIO(), engine="estimate", level="low", chunk_chars=200,
                progress=lambda done, total: calls.append((done, total)))
    total = calls[0][1]
    assert calls[0] == (0, total) and calls[-1] == (total, total)
    assert len(calls) >= 5 and [d for d, _ in calls] == sorted(d for d, _ in calls)


def test_a_sixty_thousand_letter_word_is_spoken_in_pieces():
    """Bounded: one 'word' longer than a chunk is cut between letters, no chunk over CHUNK_CHARS;
    sentences around it stay whole."""
    word = "abcdefghij" * 6000
    markup = parse_markup(f"Before it. {word} After it.")
    pieces = [m.text for m in sentence_chunks(markup)]
    assert max(len(p) for p in pieces) <= CHUNK_CHARS and len(pieces) >= 30
    assert "".join(pieces).replace(" ", "") == markup.text.replace(" ", "")
    assert pieces[0].startswith("Before it.") and pieces[-1].endswith("After it.")
    spoken = stream_text("Short. " + "x" * 1500 + " Done.", io.BytesIO(), engine="estimate", level="low",
                         fps=10.0, chunk_chars=500)
    assert spoken.chunks >= 3


def test_a_combining_mark_stays_with_its_letter():
    text = ("e\u0301" * 30)
    assert all(not p.text[0] == "\u0301" for p in sentence_chunks(parse_markup(text), 7))


def test_speech_longer_than_a_stream_spans_is_refused_where_it_runs_over(monkeypatch, tmp_path, capfd):
    """Located, and nothing left behind: no partial stream, WAV or timings, no noise from the WAV writer."""
    monkeypatch.setattr(bits_module, "frame_limit", lambda fps: 300)
    with pytest.raises(MarkupError) as info:
        encode_text_to(TEXT, tmp_path / "long.fba", audio=tmp_path / "long.wav", timings=tmp_path / "long.json",
                       engine=_SameSpeech(make_engine("espeak")), level="low", chunk_chars=150, name="long.txt")
    assert "more than one stream may span" in str(info.value)
    assert info.value.line == 1 and info.value.column > 1 and str(info.value).startswith("long.txt:1:")
    import gc
    gc.collect()
    assert not list(tmp_path.iterdir()) and "Exception ignored" not in capfd.readouterr().err


def test_say_refuses_speech_longer_than_it_renders_before_rendering(monkeypatch, tmp_path):
    import mpeg4fa.say as say_module

    monkeypatch.setattr(say_module, "MAX_SAY_SECONDS", 10.0)
    out = tmp_path / "long.mp4"
    with pytest.raises(MarkupError) as info:
        say_module.say(TEXT, out, engine="estimate")
    assert "runs past 10 s" in str(info.value) and "mpeg4fa encode" in info.value.hint
    assert not list(tmp_path.iterdir())


def test_a_source_beyond_the_parser_bound_is_parsed_in_pieces_with_its_places(monkeypatch):
    source = "\n".join(f"Line {k} says (joy, {k}, 1) hello. And more. " for k in range(1, 30))
    whole = parse_markup(source, name="f.txt")
    monkeypatch.setattr(chunks_module, "MAX_TEXT_CHARS", 120)
    pieces = list(parse_pieces(source, name="f.txt"))
    assert len(pieces) >= 10
    assert [(t.line, t.column, t.intensity) for p in pieces for t in p.tags] == \
        [(t.line, t.column, t.intensity) for t in whole.tags]
    at = 0
    for piece in pieces:  # each piece's characters sit where they sit in the whole source
        at = whole.text.index(piece.text, at)
        assert piece.places == whole.places[at:at + len(piece.text)]
        at += len(piece.text)
    bad = source + "\nthe end (joy, 99, 1)"
    with pytest.raises(MarkupError) as expected:
        parse_markup(bad, name="f.txt")
    with pytest.raises(MarkupError) as got:
        list(parse_pieces(bad, name="f.txt"))
    assert str(got.value) == str(expected.value)


def test_encode_cli_streams_text_with_audio_and_timings(tmp_path, capsys):
    from mpeg4fa.cli import main

    source = tmp_path / "talk.txt"
    source.write_text(" ".join(SENTENCES[:3]), encoding="utf-8")
    out, wav, timings = tmp_path / "talk.fba", tmp_path / "talk.wav", tmp_path / "talk.json"
    assert main(["encode", str(source), "-o", str(out), "--audio", str(wav), "--timings", str(timings)]) == 0
    err = capsys.readouterr().err
    assert re.search(r"made in [0-9.]+ s for [0-9.]+ s of speech", err) and f"wrote {out}" in err
    assert len(json.loads(timings.read_text(encoding="utf-8"))) > 10
    assert decode(out.read_bytes()).n_frames > 0
    with wave.open(str(wav), "rb") as w:
        assert w.getnframes() > 0


def test_blocks_stay_short_at_any_frame_rate():
    """--fps 255 is bounded: a block holds at most BLOCK_FRAMES frames, a whole number of intra periods."""
    assert bits_module.block_frames(25.0) == bits_module.BLOCK_FRAMES
    assert bits_module.block_frames(255.0) == bits_module.BLOCK_FRAMES
    assert bits_module.block_frames(1.0) == 60
    assert bits_module.block_frames(25.0, intra_period=7) % 7 == 0


@pytest.mark.parametrize("text", ["", "   \n\t"])
def test_empty_text_is_one_error_not_an_endless_loop(text):
    """Fuzz finding (text): parse_pieces of an empty source yielded its one piece forever."""
    from mpeg4fa.speech.chunks import parse_pieces

    assert [m.text for m in parse_pieces(text)] == [""]
    with pytest.raises(MarkupError, match="nothing to say"):
        encode_text(text, engine="estimate")
