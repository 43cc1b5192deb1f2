"""The avatar systems' viseme and blend-shape tables (spec/, mpeg4fa.spec.avatars) and the maps between them."""
import csv
from importlib import resources
from pathlib import Path

import pytest

from mpeg4fa.spec import VISEMES
from mpeg4fa.spec.avatars import (ARKIT_BLENDSHAPES, AZURE_VISEMES, OCULUS_VISEMES, POLLY_VISEMES, VISEME_TARGETS,
                                  from_azure, from_oculus, from_polly, viseme_target)
from mpeg4fa.spec.errors import SpecError
from mpeg4fa.spec.profiles import VISEME_PROFILES

MPEG4 = [v.name for v in VISEMES]
SPEC = Path(__file__).resolve().parents[2] / "spec"


def test_the_sets_have_their_published_sizes_and_names():
    assert len(ARKIT_BLENDSHAPES) == 52 and ARKIT_BLENDSHAPES[17] == "jawOpen" and ARKIT_BLENDSHAPES[-1] == "tongueOut"
    assert [v.name for v in OCULUS_VISEMES] == ["sil", "PP", "FF", "TH", "DD", "kk", "CH", "SS", "nn", "RR", "aa",
                                                "E", "ih", "oh", "ou"]
    assert [v.id for v in AZURE_VISEMES] == list(range(22))
    assert AZURE_VISEMES[21].ipa == ("p", "b", "m") and AZURE_VISEMES[0].mpeg4 == "none"
    glides = {v.id: (v.mpeg4, v.offglide) for v in AZURE_VISEMES if v.offglide}
    assert glides == {9: ("AA", "ou"), 10: ("oh", "ih"), 11: ("AA", "ih")}  # aʊ ɔɪ aɪ
    assert [v.name for v in POLLY_VISEMES] == ["sil", "p", "t", "S", "T", "f", "k", "i", "r", "s", "u", "@", "a",
                                               "e", "E", "o", "O"]


def test_every_viseme_of_every_set_has_a_target():
    for set_name, names in VISEME_PROFILES.items():
        for name in names:
            target = viseme_target(name, set_name)
            assert from_oculus(target.oculus) in MPEG4
            assert from_azure(target.azure) in MPEG4
            assert from_polly(target.polly) in MPEG4
    assert len(VISEME_TARGETS) == sum(len(names) for names in VISEME_PROFILES.values())


def test_oculus_is_the_mpeg4_set_renamed():
    """OVR's 15 visemes are MPEG-4's: the map is one-to-one both ways."""
    assert sorted(v.mpeg4 for v in OCULUS_VISEMES) == sorted(MPEG4)
    for name in MPEG4:
        assert from_oculus(viseme_target(name).oculus) == name


def test_mpeg4_to_azure_and_back_is_the_identity():
    ids = [viseme_target(name).azure for name in MPEG4]
    assert len(set(ids)) == len(ids)  # one-to-one: every MPEG-4 viseme has an Azure ID of its own
    for name in MPEG4:
        assert from_azure(viseme_target(name).azure) == name


def test_mpeg4_to_polly_and_back_where_invertible():
    """Polly shows n and l with t (one viseme 't'), so nn and DD share it; every other viseme comes back."""
    back = {name: from_polly(viseme_target(name).polly) for name in MPEG4}
    assert {name for name, again in back.items() if again != name} == {"nn"}
    assert back["nn"] == "DD" and viseme_target("nn").polly == viseme_target("DD").polly


def test_every_azure_id_and_polly_viseme_reaches_a_viseme_of_like_shape():
    closures = {v.id for v in AZURE_VISEMES if v.mpeg4 == "PP"}
    assert closures == {21}
    assert from_polly("p") == "PP" and from_polly("sil") == "none" and from_polly("a") == "AA"
    assert from_polly("u") == from_azure(7) == "ou"


def test_chinese_visemes_go_out_as_their_nearest_shapes():
    assert viseme_target("bpm", "zh").oculus == "PP" and viseme_target("bpm", "zh").azure == 21
    assert viseme_target("a", "zh").oculus == "aa" and viseme_target("uv", "zh").polly == "u"
    assert from_azure(viseme_target("f", "zh").azure) == "FF"


def test_unknown_names_and_ids_are_spec_errors():
    for bad in (22, -1, "3", None, True):
        with pytest.raises(SpecError, match="Azure viseme ID"):
            from_azure(bad)
    with pytest.raises(SpecError, match="Polly viseme 'x'"):
        from_polly("x")
    with pytest.raises(SpecError, match="OVR viseme"):
        from_oculus("AA")
    with pytest.raises(SpecError, match="zh viseme 'PP'"):
        viseme_target("PP", "zh")


def test_the_arkit_deformer_drives_only_arkit_blend_shapes():
    with (resources.files("mpeg4fa.face") / "data" / "arkit_faps.csv").open(encoding="utf-8") as f:
        units = {row["unit"] for row in csv.DictReader(f)}
    assert units <= set(ARKIT_BLENDSHAPES)


def test_the_generic_head_carries_the_52_blend_shapes(generic_face):
    assert set(generic_face.mesh.face_units.names) == set(ARKIT_BLENDSHAPES)


def test_the_readme_names_each_table():
    readme = (SPEC / "README.md").read_text(encoding="utf-8")
    for name in ("arkit_blendshapes.csv", "oculus_visemes.csv", "azure_visemes.csv", "polly_visemes.csv",
                 "viseme_targets.csv"):
        assert f"`{name}`" in readme
