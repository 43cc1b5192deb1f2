"""`decode` to .fap + .bap and `encode` of .bap (+ .fap) back to .fba: files written, refused command
lines (exit 2) and bad .bap files (exit 1), each with one error line and no output left behind."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mpeg4fa import spec
from mpeg4fa.atomic import PARTIAL_MARK
from mpeg4fa.cli import main
from mpeg4fa.fba import EncodeOptions, decode, demo_stream, encode
from mpeg4fa.fba.stream import BODY, FACE, FapStream
from mpeg4fa.formats import read_bap, read_fap

VECTORS = Path(__file__).resolve().parents[2].parent / "shared" / "vectors" / "fba"
SENT = [0, 31, 37, 183, 185]  # BAPs 1, 32, 38, 184, 186


def made_stream(object_mask: int, n: int = 20) -> FapStream:
    """A stream with the given parts; values on the quantiser grid, so they survive .fba exactly."""
    s = FapStream.empty(n, object_mask=object_mask)
    k = np.arange(n)
    if object_mask & BODY:
        s.bap_mask[:, SENT] = True
        s.bap_values[:, SENT] = (np.sin(k[:, None] / 3 + np.arange(len(SENT))) * 30).astype(np.int32) \
            * spec.BAP_QUANT_STEP[SENT]
    if object_mask & FACE:
        s.fap_mask[:, [2, 18]] = True
        s.fap_values[:, 2] = (k % 7) * 20 * spec.QUANT_STEP[2]
        s.fap_values[:, 18] = -(k % 5) * 8 * spec.QUANT_STEP[18]
    s.source_fps = 25.0
    return s


@pytest.fixture
def face_body(tmp_path: Path) -> Path:
    path = tmp_path / "both.fba"
    path.write_bytes(encode(made_stream(FACE | BODY), EncodeOptions()))
    return path


@pytest.fixture
def body_only(tmp_path: Path) -> Path:
    path = tmp_path / "body.fba"
    path.write_bytes(encode(made_stream(BODY), EncodeOptions()))
    return path


def run(capsys, *argv) -> tuple[int, str]:
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:  # argparse
        code = exc.code
    return code, capsys.readouterr().err


def files(folder: Path) -> set[str]:
    return {p.name for p in folder.iterdir()}


def test_decode_face_body_writes_fap_and_bap(face_body: Path, tmp_path: Path, capsys) -> None:
    code, err = run(capsys, "decode", face_body, "-o", tmp_path / "out.fap")
    assert code == 0, err
    assert "out.fap (face) and" in err and "out.bap (body)" in err
    original = decode(face_body)
    body = read_bap(tmp_path / "out.bap")
    assert (body.bap_mask == original.bap_mask).all() and (body.bap_values == original.bap_values).all()
    face = read_fap(tmp_path / "out.fap")
    assert (face.fap_values == original.fap_values).all() and not face.bap_mask.any()
    assert (tmp_path / "out.bap").read_text().startswith("3.1 out.bap 25 20\n")


def test_decode_bap_option_names_the_body_file(face_body: Path, tmp_path: Path, capsys) -> None:
    (tmp_path / "body").mkdir()
    code, err = run(capsys, "decode", face_body, "-o", tmp_path / "out.fap", "--bap", tmp_path / "body" / "b.bap")
    assert code == 0, err
    assert (tmp_path / "body" / "b.bap").is_file() and not (tmp_path / "out.bap").exists()


@pytest.mark.parametrize("how", [["-o", "{dir}/only.bap"], ["--bap-only", "-o", "{dir}/only.bap"]])
def test_decode_body_only_output(face_body: Path, tmp_path: Path, capsys, how: list[str]) -> None:
    out = tmp_path / "out"
    out.mkdir()
    code, err = run(capsys, "decode", face_body, *[a.format(dir=out) for a in how])
    assert code == 0, err
    assert files(out) == {"only.bap"}
    assert (read_bap(out / "only.bap").bap_values == decode(face_body).bap_values).all()


def test_encode_fap_with_bap_rebuilds_the_stream(face_body: Path, tmp_path: Path, capsys) -> None:
    assert run(capsys, "decode", face_body, "-o", tmp_path / "x.fap")[0] == 0
    code, err = run(capsys, "encode", tmp_path / "x.fap", "--bap", tmp_path / "x.bap", "-o", tmp_path / "y.fba")
    assert code == 0, err
    a, b = decode(face_body), decode(tmp_path / "y.fba")
    for field in ("fap_mask", "fap_values", "bap_mask", "bap_values", "object_mask"):
        assert (getattr(a, field) == getattr(b, field)).all(), field


def test_encode_bap_alone_is_a_body_only_stream(body_only: Path, tmp_path: Path, capsys) -> None:
    assert run(capsys, "decode", body_only, "-o", tmp_path / "m.bap")[0] == 0
    code, err = run(capsys, "encode", tmp_path / "m.bap", "-o", tmp_path / "m.fba")
    assert code == 0, err
    again = decode(tmp_path / "m.fba")
    assert set(again.object_mask.tolist()) == {BODY}
    assert (again.bap_values == decode(body_only).bap_values).all()
    code, _ = run(capsys, "info", tmp_path / "m.bap")
    assert code == 0


@pytest.mark.parametrize("case", ["body stream to .fap", "face stream to .bap", "face stream with --bap",
                                  "--bap with a .bap -o", "--bap is -o"])
def test_refused_decode_command_lines(case: str, body_only: Path, tmp_path: Path, capsys) -> None:
    face = tmp_path / "face.fba"
    face.write_bytes(encode(demo_stream()))
    out = tmp_path / "out"
    out.mkdir()
    argv = {
        "body stream to .fap": [body_only, "-o", out / "x.fap"],
        "face stream to .bap": [face, "-o", out / "x.bap"],
        "face stream with --bap": [face, "-o", out / "x.fap", "--bap", out / "x.bap"],
        "--bap with a .bap -o": [body_only, "-o", out / "x.bap", "--bap", out / "y.bap"],
        "--bap is -o": [body_only, "-o", out / "x.fap", "--bap", out / "x.fap"],
    }[case]
    code, err = run(capsys, "decode", *argv)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert files(out) == set()


def test_face_only_decode_writes_no_bap(tmp_path: Path, capsys) -> None:
    face = tmp_path / "face.fba"
    face.write_bytes(encode(demo_stream()))
    assert run(capsys, "decode", face, "-o", tmp_path / "f.fap")[0] == 0
    assert not (tmp_path / "f.bap").exists()


BAD_BAP = {
    "wrong value count": ("3.1 b 25 1\n" + " ".join(["1", "1"] + ["0"] * 184) + "\n0 340\n", "3:6:"),
    "bad mask": ("3.1 b 25 1\n" + " ".join(["1", "x"] + ["0"] * 184) + "\n0 340 340\n", "2:3:"),
    "truncated": ("3.1 b 25 2\n" + " ".join(["1"] + ["0"] * 185) + "\n0 340\n" + " ".join(["1"] + ["0"] * 90),
                  "4:"),
    "value out of range": ("3.1 b 25 1\n" + " ".join(["1"] + ["0"] * 185) + "\n0 99999999999\n", "3:3:"),
}


@pytest.mark.parametrize("case", sorted(BAD_BAP))
def test_bad_bap_is_one_located_error_and_no_output(case: str, tmp_path: Path, capsys) -> None:
    text, where = BAD_BAP[case]
    bad = tmp_path / "bad.bap"
    bad.write_text(text)
    face = tmp_path / "f.fap"
    face.write_text("2.1 f 25 1\n" + " ".join(["0", "0", "1"] + ["0"] * 65) + "\n0 10\n")
    for argv in ([bad, "-o", tmp_path / "o.fba"], [face, "--bap", bad, "-o", tmp_path / "o.fba"]):
        code, err = run(capsys, "encode", *argv)
        assert code == 1 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
        assert f"{bad}:{where}" in err, err
        assert not (tmp_path / "o.fba").exists()
        assert not [p for p in tmp_path.iterdir() if PARTIAL_MARK in p.name]


def test_refused_encode_command_lines(face_body: Path, tmp_path: Path, capsys) -> None:
    assert run(capsys, "decode", face_body, "-o", tmp_path / "x.fap")[0] == 0
    cases = [
        [face_body, "--bap", tmp_path / "x.bap", "-o", tmp_path / "o.fba"],          # .fba INPUT
        [tmp_path / "x.bap", "--bap", tmp_path / "x.bap", "-o", tmp_path / "o.fba"],  # .bap INPUT
        [tmp_path / "x.fap", "--bap", tmp_path / "o.fba", "-o", tmp_path / "o.fba"],  # --bap is -o
        ["Hello there", "--bap", tmp_path / "x.bap", "-o", tmp_path / "o.fba"],       # text INPUT
    ]
    for argv in cases:
        code, err = run(capsys, "encode", *argv)
        assert code == 2 and "--bap" in err and len(err.strip().splitlines()) == 1, (argv, err)
        assert not (tmp_path / "o.fba").exists()


def test_help_text(capsys) -> None:
    with pytest.raises(SystemExit):
        main(["decode", "--help"])
    out = capsys.readouterr().out
    assert "--bap FILE" in out and "--bap-only" in out and "OUT.bap" in out
    with pytest.raises(SystemExit):
        main(["encode", "--help"])
    assert "--bap FILE" in capsys.readouterr().out


def test_real_face_body_stream_round_trips_through_the_cli(tmp_path: Path, capsys) -> None:
    path = VECTORS / "yes_0.fba"
    if not path.is_file():
        pytest.skip(f"../shared/vectors not present: {path} is a real face+body stream")
    assert run(capsys, "decode", path, "-o", tmp_path / "a.fap")[0] == 0
    assert run(capsys, "encode", tmp_path / "a.fap", "--bap", tmp_path / "a.bap", "-o", tmp_path / "b.fba")[0] == 0
    assert run(capsys, "decode", tmp_path / "b.fba", "-o", tmp_path / "b.fap")[0] == 0
    body = lambda p: p.read_text().split("\n", 1)[1]  # noqa: E731  (the header names the file)
    assert body(tmp_path / "a.bap") == body(tmp_path / "b.bap")
    assert body(tmp_path / "a.fap") == body(tmp_path / "b.fap")


def test_linked_output_needs_an_explicit_bap(face_body: Path, tmp_path: Path, capsys) -> None:
    target = tmp_path / "real.fap"
    target.write_text("")
    link = tmp_path / "link.fap"
    link.symlink_to(target)
    code, err = run(capsys, "decode", face_body, "-o", link)
    assert code == 2 and "--bap FILE" in err and not (tmp_path / "link.bap").exists()
    assert target.read_text() == ""
    code, err = run(capsys, "decode", face_body, "-o", link, "--bap", tmp_path / "b.bap")
    assert code == 0, err
    assert target.read_text().startswith("2.1 ") and (tmp_path / "b.bap").is_file()
