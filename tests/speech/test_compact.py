"""Smaller high-level streams from text (mpeg4fa.speech.compact) decode to the same face as before:
FAP 1/2 fields rewritten to equivalent ones, FAP 2 sent only where it pays."""
import numpy as np
import pytest

from mpeg4fa.decoded import resolve
from mpeg4fa.fba import EncodeOptions, FapStream, decode, encode
from mpeg4fa.spec import QUANT_STEP
from mpeg4fa.spec.profiles import expand_high_level
from mpeg4fa.speech.compact import compact_expressions, compact_visemes, expression_masks
from mpeg4fa.speech.encoder import encode_text

from .test_encoder import Replay

PLAIN = "Would you want me to tell you the latest info about hotels and book reservations?"
TAGGED = "(joy, 40, 0.5) Hello there, (sadness, 30, 1) my old friend. (joy, 0, 0.3) How are you?"
ZH = "(joy, 30, 0.5)你好，世界！"
MIXED = "(surprise, 30, 0.3) Hello 你好, my friend."


@pytest.fixture(scope="module")
def engine():
    return Replay()  # each text spoken once: both encodings see the same phoneme times


def shown(stream, options):
    """What a decoder shows at every frame of the grid (skipped frames repeat the one before)."""
    back = decode(encode(stream, options))
    return np.repeat(resolve(back), back.skip + 1, axis=0)


@pytest.mark.parametrize("text", [PLAIN, TAGGED, ZH, MIXED])
@pytest.mark.parametrize("level", ["high", "both"])
def test_compact_streams_show_the_same_face_and_are_smaller(engine, text, level):
    new = encode_text(text, engine=engine, level=level)
    old = encode_text(text, engine=engine, level=level, compact=False)
    for options in (new.coding(), new.coding(fap_quant=1)):
        a, b = shown(new.stream, options), shown(old.stream, options)
        assert a.shape == b.shape == (len(new.stream), 68)
        # FAP 1/2 decode alike (blend and intensities: 63 is a multiple of both quantisers); a low-level FAP
        # whose frames turned intra may land half a quantiser step the other way
        assert (np.abs(a - b) <= QUANT_STEP * options.fap_quant / 2 + 1e-9).all()
        if level == "high" and text in (PLAIN, TAGGED):  # no low-level FAP: the very same values
            assert np.abs(a - b).max() < 1e-9
    smaller, before = len(encode(new.stream, new.coding())), len(encode(old.stream, old.coding()))
    assert smaller < before if text in (PLAIN, TAGGED) else smaller <= before


def test_text_without_expression_tags_sends_no_fap2(engine):
    enc = encode_text(PLAIN, engine=engine)
    assert enc.stream.fap_mask[:, 0].all() and not enc.stream.fap_mask[:, 1].any()
    back = decode(encode(enc.stream, enc.coding()))
    assert sorted(back.intra) == [0]  # one intra frame: the mask never changes


def test_tagged_text_sends_fap2_at_least_where_it_changes(engine):
    enc = encode_text(TAGGED, engine=engine)
    old = encode_text(TAGGED, engine=engine, compact=False).stream
    sent = enc.stream.fap_mask[:, 1]
    assert sent.any()
    # every frame whose expression differs from the one before is sent (where nothing is sent, it holds)
    mixture = expand_high_level(np.zeros((len(old), 4), np.int64), old.expression.astype(np.int64))
    moved = np.r_[np.abs(mixture[0]).max() > 0, np.abs(np.diff(mixture, axis=0)).max(axis=1) > 1e-9]
    assert sent[moved].all()
    # joy settles 0.6 s in and stays: FAP 2 goes out over the fade, then holds (one intra frame to drop it)
    settled = encode_text("(joy, 30, 0.6) Good morning, and welcome to the station.", engine=engine)
    mask = settled.stream.fap_mask[:, 1]
    assert mask[:10].all() and not mask[-20:].any()
    back = decode(encode(settled.stream, settled.coding()))
    assert np.abs(np.repeat(resolve(back), back.skip + 1, axis=0)[-1]).max() > 0  # joy still shows at the end


def test_fap1_fields_that_do_not_matter_repeat_their_last_value():
    # (select1, select2, blend, def): a move 4 -> 12, a hold at 12, a move 12 -> 1, a hold at 1
    rows = np.array([[12, 4, 20, 0], [12, 4, 50, 0], [12, 4, 63, 0], [12, 12, 63, 0], [12, 12, 7, 0],
                     [1, 12, 30, 0], [1, 12, 63, 0], [1, 1, 63, 0]])
    out = compact_visemes(rows)
    shows = expand_high_level(out, np.zeros((len(out), 6), np.int64))
    want = expand_high_level(rows, np.zeros((len(rows), 6), np.int64))
    assert np.abs(shows - want).max() < 1e-9
    assert (out[2:5] == out[2]).all()  # the hold at 12 writes one row: folded into a skip count
    changed = (np.diff(out[:, :3], axis=0) != 0).sum(axis=1)
    assert changed.max() <= 2 and (changed[[4, 5]] >= 1).all()
    # the move 12 -> 1 keeps 12 in its slot: only one select changes
    assert (np.diff(out[4:6, :2], axis=0) != 0).sum() == 1


def test_fap2_slots_keep_their_expression_and_empty_slots_hold():
    # joy fades out while sadness fades in, crossing over; then sadness alone
    rows = np.array([[1, 30, 0, 0, 0, 0], [1, 20, 2, 10, 0, 0], [2, 20, 1, 10, 0, 0], [2, 30, 0, 0, 0, 0],
                     [2, 30, 0, 0, 0, 0]])
    out = compact_expressions(rows)
    zero = np.zeros((len(rows), 4), np.int64)
    assert np.abs(expand_high_level(zero, out) - expand_high_level(zero, rows)).max() < 1e-9
    assert (out[3] == out[4]).all()  # the repeated frame stays a repeat (folded into a skip count)
    # the fields chosen cost no more bits than the fields as given, and than the slots swapped
    swapped = rows.copy()
    swapped[:, :4] = rows[:, [2, 3, 0, 1]]
    assert _fap2_bits(out) <= min(_fap2_bits(rows), _fap2_bits(swapped))


def _fap2_bits(rows):
    s = FapStream.empty(len(rows))
    s.fap_mask[:, 1] = True
    s.expression[:] = rows
    return len(encode(s, EncodeOptions(fap_quant=3, optimize=True))) * 8


def test_expression_masks_cover_every_change_and_end_with_all_frames():
    rows = np.zeros((100, 6), np.int64)
    rows[10:20, :2] = [1, 5]
    rows[10:20, 1] = np.arange(10) + 1
    rows[20:, :2] = [1, 10]
    masks = expression_masks(rows)
    assert masks[-1].all() and len(masks) >= 3
    for mask in masks:
        assert mask[10:20].all()
    assert expression_masks(np.zeros((5, 6), np.int64)) == []


def test_mandarin_high_level_keeps_its_face(engine):
    """All-Chinese speech: no FAP 1, low-level FAPs in every frame, FAP 2 where it pays; same face."""
    new = encode_text("女人去绿色的地方。", engine=engine)
    old = encode_text("女人去绿色的地方。", engine=engine, compact=False)
    assert not new.stream.fap_mask[:, 0].any() and not new.stream.fap_mask[:, 1].any()
    options = EncodeOptions(**{"optimize": True, "fap_quant": 3})
    assert (np.abs(shown(new.stream, options) - shown(old.stream, options)) <= QUANT_STEP * 1.5 + 1e-9).all()
