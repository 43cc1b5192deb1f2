"""Mandarin: hanzi -> pinyin (phrase-aware) -> initial / glide / main vowel / ending -> Chinese visemes."""
import pytest

from mpeg4fa.spec import CHINESE_VISEMES
from mpeg4fa.speech.mandarin import syllable_visemes, syllables


def test_ni_hao_shi_jie_gives_the_expected_visemes_and_keeps_tones():
    got = syllables("你好，世界")
    assert [s.text for s in got] == ["你", "好", "世", "界"]
    assert [s.position for s in got] == [0, 1, 3, 4]
    assert [s.tone for s in got] == [3, 3, 4, 4]
    assert [s.pinyin for s in got] == ["ni3", "hao3", "shi4", "jie4"]
    assert [v for s in got for v in s.visemes] == ["dtnl", "i", "gkh", "a", "o", "zhchsh", "jqx", "i", "e"]


@pytest.mark.parametrize("text,reading", [("重庆", ["chong2", "qing4"]), ("银行", ["yin2", "hang2"]),
                                          ("行走", ["xing2", "zou3"]), ("重要", ["zhong4", "yao4"])])
def test_polyphones_follow_their_words(text, reading):
    assert [s.pinyin for s in syllables(text)] == reading


@pytest.mark.parametrize("initial,final,visemes", [
    ("", "uo", ("uv", "o")), ("", "ai", ("a", "i")), ("x", "iong", ("jqx", "i", "o", "ng")),
    ("", "ve", ("uv", "e")), ("", "vn", ("uv", "n")), ("ch", "uang", ("zhchsh", "uv", "a", "ng")),
    ("", "ueng", ("uv", "e", "ng")), ("r", "i", ("r",)), ("s", "i", ("zcs",)), ("zh", "i", ("zhchsh",)),
    ("", "er", ("r",)), ("h", "uar", ("gkh", "uv", "a", "r")), ("l", "iou", ("dtnl", "i", "o", "uv")),
    ("g", "uei", ("gkh", "uv", "e", "i")), ("b", "ing", ("bpm", "i", "ng")), ("m", "ao", ("bpm", "a", "o")),
    ("f", "eng", ("f", "e", "ng")), ("q", "v", ("jqx", "uv")), ("", "i", ("i",)),
])
def test_syllable_decomposition(initial, final, visemes):
    assert syllable_visemes(initial, final) == visemes


def test_every_chinese_viseme_is_reachable_and_other_text_is_skipped():
    text = "八发大哥你吃日字鱼饿我爱安阿英 hello, 世界 (2026)"
    seen = {v for s in syllables(text) for v in s.visemes}
    assert seen == {v.name for v in CHINESE_VISEMES}
    assert "".join(s.text for s in syllables(text)) == "八发大哥你吃日字鱼饿我爱安阿英世界"
    assert syllables("no hanzi here") == []
