"""Images (--texture, --front, the texture command) are read within a pixel ceiling checked from the
header; a damaged, truncated or foreign file is one RenderError naming the file (issue 26 item 4)."""
from __future__ import annotations

import struct
import zlib

import numpy as np
import pytest
from PIL import Image

from mpeg4fa.render.errors import RenderError
from mpeg4fa.render.images import MAX_PIXELS, read_image


def png_header_only(width: int, height: int) -> bytes:
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(b"")) + chunk(b"IEND", b""))


@pytest.fixture
def jpeg(tmp_path):
    path = tmp_path / "ok.jpg"
    Image.fromarray(np.full((32, 48, 3), 120, np.uint8)).save(path)
    return path


def test_a_good_image(jpeg):
    assert read_image(jpeg, "photo").shape == (32, 48, 3)
    assert read_image(jpeg.read_bytes(), "photo").shape == (32, 48, 3)


@pytest.mark.parametrize("name, make, words", [
    ("trunc.jpg", lambda ok: ok[: len(ok) // 2], "damaged or truncated"),
    ("text.png", lambda ok: b"just some text\n", "not an image: it is text"),
    ("doc.png", lambda ok: b"%PDF-1.7\n" + bytes(40), "(a PDF document)"),
    ("empty.png", lambda ok: b"", "the file is empty"),
    ("wide.png", lambda ok: png_header_only(8193, 8192), f"more than the {MAX_PIXELS:,} pixels"),
    ("bomb.png", lambda ok: png_header_only(50_000, 50_000), f"more than the {MAX_PIXELS:,} pixels read"),
])
def test_bad_images_are_one_error_naming_the_file(tmp_path, jpeg, name, make, words):
    path = tmp_path / name
    path.write_bytes(make(jpeg.read_bytes()))
    with pytest.raises(RenderError) as info:
        read_image(path, "texture image")
    assert str(info.value).startswith(f"{path}: ") and words in str(info.value) and "\n" not in str(info.value)


def test_a_strip_longer_than_a_side_may_be_is_refused_before_decoding():
    """Fuzz finding (image:45177@0): a 2 kB PNG of 16 x 3,997,696 grey pixels, inside the pixel ceiling, took
    656 MiB to read; no photo or texture is a strip, so a side is at most MAX_SIDE."""
    import io

    from PIL import Image

    from mpeg4fa.render.errors import RenderError
    from mpeg4fa.render.images import MAX_SIDE, read_image

    data = io.BytesIO()
    Image.new("L", (16, MAX_SIDE + 1)).save(data, "PNG")
    with pytest.raises(RenderError, match="a side"):
        read_image(data.getvalue(), "photo", "strip.png")
    grey = io.BytesIO()
    Image.fromarray(np.arange(48, dtype=np.uint8).reshape(6, 8), "L").save(grey, "PNG")
    pixels = read_image(grey.getvalue(), "photo")
    assert pixels.shape == (6, 8, 3) and (pixels == np.arange(48).reshape(6, 8, 1)).all()
