"""Xface .fdp XML: reading a small file written here, 0-based FAPs, to_fdp, and faults at line:column."""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.fdp import Fdp, FdpError, XfaceFdp, read_xface_fdp, xface_from_xml

from .textpos import place

SAMPLE = """<?xml version="1.0" encoding="UTF-8" standalone="no" ?>
<xfdp>
  <!-- a made-up head in the layout of Xface's files -->
  <head>
    <file version="0.2"/>
    <fapu ENS0="51" ES0="69.5" IRISD0="16" MNS0="30" MW0="50"/>
    <translation x="0" y="-1" z="-659"/>
    <rotation axis_angle="0.4" axis_x="-1" axis_y="0" axis_z="0"/>
  </head>
  <source>
    <entity alias="Rest" category="Expression">
      <mesh file="head.wrl" format="wrl"/>
      <bind item="LowerTeeth" submesh="head.wrl_1"/>
    </entity>
    <entity alias="Smile" category="Expression">
      <mesh file="head_smile.wrl" format="wrl"/>
    </entity>
  </source>
  <fdp affects="head.wrl_0" index="2" name="2.1">
    <indices>0 1 2 3 </indices>
    <influence fap="2" type="RaisedCosInfluenceSph" weight="0.3"/>
  </fdp>
  <fdp affects="head.wrl_0" index="0" name="8.3">
    <indices>0 4</indices>
    <influence fap="52" type="RaisedCosInfluenceSph" weight="0.2"/>
    <influence fap="58" type="RaisedCosInfluenceWaveY" weight="-0.1"/>
  </fdp>
  <fdp affects="head.wrl_0" index="4" name="2.10">
    <indices/>
  </fdp>
  <fdp affects="head.wrl_1" index="1" name="2.1">
    <indices>0 1</indices>
    <influence fap="2" type="RaisedCosInfluenceSph" weight="0.3"/>
  </fdp>
</xfdp>
"""
SKIN = np.arange(15.0).reshape(5, 3)
TEETH = np.array([[0.0, -1, 0], [0, -2, 0]])


def parse(text: str = SAMPLE) -> XfaceFdp:
    return xface_from_xml(text, "alice.fdp")


def error(text: str | bytes) -> FdpError:
    with pytest.raises(FdpError) as info:
        xface_from_xml(text, "alice.fdp")
    return info.value


def assert_at(err: FdpError, text: str, needle: str, nth: int = 0) -> None:
    assert (err.line, err.column) == place(text, needle, nth), str(err)
    assert str(err).startswith(f"alice.fdp:{err.line}:{err.column}: ")


# ---- reading ------------------------------------------------------------------------------------


def test_head_and_source():
    x = parse()
    assert x.version == "0.2"
    assert x.fapu == {"IRISD0": 16.0, "ES0": 69.5, "ENS0": 51.0, "MNS0": 30.0, "MW0": 50.0}
    np.testing.assert_array_equal(x.translation, [0, -1, -659])
    np.testing.assert_array_equal(x.rotation, [-1, 0, 0, 0.4])  # axis first, angle last
    assert x.meshes == [("Rest", "head.wrl"), ("Smile", "head_smile.wrl")]
    assert x.path == "alice.fdp"


def test_points_influences_and_indices_of_the_primary_entries():
    x = parse()
    assert list(x.points) == ["2.1", "2.10", "8.3"]  # standard order
    assert x.points["2.1"] == ("head.wrl_0", 2)  # the first <fdp> for 2.1, not the teeth one
    assert x.influences["2.1"] == [(3, "RaisedCosInfluenceSph", 0.3)]  # fap="2" is FAP 3, open_jaw
    assert x.influences["8.3"] == [(53, "RaisedCosInfluenceSph", 0.2), (59, "RaisedCosInfluenceWaveY", -0.1)]
    assert x.influences["2.10"] == []
    np.testing.assert_array_equal(x.indices["2.1"], [0, 1, 2, 3])
    assert x.indices["2.10"].shape == (0,)


def test_every_entry_is_kept_with_its_line():
    x = parse()
    assert [(e.label, e.submesh, e.index) for e in x.entries] == [
        ("2.1", "head.wrl_0", 2), ("8.3", "head.wrl_0", 0), ("2.10", "head.wrl_0", 4), ("2.1", "head.wrl_1", 1)]
    teeth = x.entries[3]
    assert (teeth.line, teeth.column) == place(SAMPLE, '<fdp affects="head.wrl_1"')
    assert teeth.influences[0].fap == 3


def test_to_fdp_resolves_vertices_and_carries_fapu():
    fdp = parse().to_fdp({"head.wrl_0": SKIN, "head.wrl_1": TEETH}, name="alice")
    assert isinstance(fdp, Fdp)
    assert fdp.labels == ("2.1", "2.10", "8.3") and fdp.name == "alice"
    np.testing.assert_array_equal(fdp.point("2.1"), SKIN[2])
    np.testing.assert_array_equal(fdp.point("8.3"), SKIN[0])
    np.testing.assert_array_equal(fdp.point("2.10"), SKIN[4])
    assert fdp.fapu == {"IRISD0": 16.0, "ES0": 69.5, "ENS0": 51.0, "MNS0": 30.0, "MW0": 50.0}
    # only the primary entries need their submesh
    assert parse().to_fdp({"head.wrl_0": SKIN}) == parse().to_fdp({"head.wrl_0": SKIN, "head.wrl_1": TEETH})


def test_to_fdp_names_the_label_when_a_vertex_is_missing():
    x = parse()
    with pytest.raises(FdpError) as info:
        x.to_fdp({"other": SKIN})
    err = info.value
    assert "feature point 2.1 is on submesh 'head.wrl_0'" in err.problem and "other" in err.hint
    assert (err.line, err.column) == place(SAMPLE, '<fdp affects="head.wrl_0" index="2"')
    with pytest.raises(FdpError, match="feature point 2.10 is vertex 4 of submesh 'head.wrl_0', which has 3") as info:
        x.to_fdp({"head.wrl_0": SKIN[:3]})
    assert info.value.line == place(SAMPLE, 'name="2.10"')[0]
    with pytest.raises(ValueError, match=r"shape \(V, 3\)"):
        x.to_fdp({"head.wrl_0": SKIN[:, :2]})
    with pytest.raises(FdpError, match="feature point 2.1: .*finite"):
        x.to_fdp({"head.wrl_0": np.full((5, 3), np.nan)})


def test_a_file_without_head_gives_no_fapu():
    x = parse('<xfdp><fdp affects="m" index="0" name="9.3"/></xfdp>')
    assert x.fapu == {} and x.version == ""
    np.testing.assert_array_equal(x.rotation, [0, 0, 1, 0])
    assert x.to_fdp({"m": [[1, 2, 3]]}).fapu is None


def test_bytes_in_another_declared_encoding():
    text = SAMPLE.replace('encoding="UTF-8"', 'encoding="ISO-8859-1"').replace("made-up", "mad\u00e9-up")
    assert parse(text.encode("latin-1")).points == parse().points
    assert parse(text).points == parse().points  # str input: the declaration is overridden


def test_read_from_file(tmp_path):
    path = tmp_path / "alice.fdp"
    path.write_text(SAMPLE, encoding="utf-8")
    assert read_xface_fdp(path).points == parse().points
    with pytest.raises(FdpError, match="no such file"):
        read_xface_fdp(tmp_path / "missing.fdp")


# ---- faults at line:column --------------------------------------------------------------------------


def test_xml_syntax_error():
    text = SAMPLE.replace('<indices>0 4</indices>', '<indices>0 4</indices')
    err = error(text)
    assert "invalid XML" in err.problem
    assert err.line == place(text, "<indices>0 4</indices")[0] + 1


def test_empty_and_non_xml():
    assert "invalid XML" in error("").problem
    assert "invalid XML" in error(b"\x00\x01\x02").problem


def test_root_must_be_xfdp():
    text = '<?xml version="1.0"?>\n<face/>'
    err = error(text)
    assert "root element is <face>" in err.problem
    assert_at(err, text, "<face/>")


def test_doctype_is_refused():
    text = '<?xml version="1.0"?>\n<!DOCTYPE x [<!ENTITY a "aaaa">]>\n<xfdp>&a;</xfdp>'
    err = error(text)
    assert "DTD" in err.problem and err.line == 2


@pytest.mark.parametrize("old, new, needle, message", [
    ('name="8.3"', 'name="12.1"', '12.1"', "unknown feature point label '12.1'"),
    ('weight="-0.1"', 'weight="lots"', 'lots"', "weight= of <influence> must be a number, got 'lots'"),
    ('fap="58"', 'fap="68"', '68"', "fap= of <influence> must be an integer in 0..67, got '68'"),
    ('fap="58"', 'fap="-1"', '-1" type="RaisedCosInfluenceWaveY"', "must be an integer in 0..67"),
    ('index="0" name="8.3"', 'index="x" name="8.3"', 'x" name="8.3"', "index= of <fdp> must be an integer"),
    ('<indices>0 4</indices>', '<indices>0 4.5</indices>', "4.5", "vertex index must be a non-negative integer"),
    ('<indices>0 4</indices>', '<indices>0\n -4</indices>', "-4", "vertex index must be a non-negative integer"),
    ('MW0="50"', 'MW0="0"', '0"/>', "FAPU distance MW0 must be positive"),
    ('ES0="69.5"', 'ES0="1e999"', '1e999', "ES0= of <fapu> must be a number"),
    ('y="-1"', 'y="up"', 'up"', "y= of <translation> must be a number"),
])
def test_bad_values_point_at_the_value(old, new, needle, message):
    assert old in SAMPLE
    text = SAMPLE.replace(old, new)
    err = error(text)
    assert message in err.problem, str(err)
    assert_at(err, text, needle)


def test_missing_attribute_points_at_the_element():
    text = SAMPLE.replace(' type="RaisedCosInfluenceWaveY"', "")
    err = error(text)
    assert "<influence> lacks the attribute type=" in err.problem
    assert_at(err, text, '<influence fap="58"')


def test_same_label_twice_on_one_submesh():
    text = SAMPLE.replace('affects="head.wrl_1" index="1" name="2.1"', 'affects="head.wrl_0" index="1" name="2.1"')
    err = error(text)
    assert "second <fdp> for 2.1 on submesh 'head.wrl_0'" in err.problem
    assert_at(err, text, '<fdp affects="head.wrl_0" index="1"')


def test_non_utf8_bytes_are_located():
    raw = SAMPLE.encode("utf-8").replace(b"made-up", b"made\xff-up")
    err = error(raw)
    assert "invalid XML" in err.problem and err.line == 3
