"""A file of another kind given as a stream is named by its signature, the same way by every reader
(issue 26: a JPEG renamed fake.fba read as "NUL byte: this is not a text .fap file")."""
from __future__ import annotations

import pytest

from mpeg4fa.fba import FbaError, decode
from mpeg4fa.filetype import foreign_kind
from mpeg4fa.formats import FormatError, read_stream, sniff

FOREIGN = {
    "jpeg": (b"\xff\xd8\xff\xe0\x00\x10JFIF\x00" + bytes(100), "0xFFD8FFE0 (a JPEG image)"),
    "png": (b"\x89PNG\r\n\x1a\n" + bytes(100), "(a PNG image)"),
    "wav": (b"RIFF\x24\x00\x00\x00WAVEfmt " + bytes(100), "(a WAV audio file)"),
    "mp4": (b"\x00\x00\x00\x20ftypisom" + bytes(100), "(an MP4/QuickTime file)"),
    "zip": (b"PK\x03\x04" + bytes(100), "(a ZIP archive)"),
    "glb": (b"glTF\x02\x00\x00\x00" + bytes(100), "(a GLB (binary glTF) model)"),
    "gzip": (b"\x1f\x8b\x08\x00" + bytes(100), "(a gzip-compressed file)"),
    "pdf": (b"%PDF-1.7\n" + bytes(100), "(a PDF document)"),
}


@pytest.mark.parametrize("kind", sorted(FOREIGN))
def test_read_stream_names_the_foreign_kind(tmp_path, kind):
    data, words = FOREIGN[kind]
    path = tmp_path / "fake.fba"
    path.write_bytes(data)
    with pytest.raises(FormatError) as info:
        sniff(path)
    assert words in str(info.value) and str(info.value).startswith(str(path))
    with pytest.raises(FormatError, match="not an FBA stream or a .fap/.bap text file"):
        read_stream(path)


@pytest.mark.parametrize("kind", sorted(FOREIGN))
def test_decoder_names_it_the_same_way(tmp_path, kind):
    data, words = FOREIGN[kind]
    with pytest.raises(FbaError) as info:
        decode(data)
    assert words in str(info.value)


def test_text_and_streams_are_not_foreign():
    assert foreign_kind(b"2.1 talk 25 100\n") is None
    assert foreign_kind(b"\x00\x00\x01\xba\x80") == "an FBA stream"
