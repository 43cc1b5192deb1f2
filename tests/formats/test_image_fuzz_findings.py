"""Images the fuzz campaigns of issue 26 item 9 found (image:1808@1: a PNG chunk claiming 4 GB, a MemoryError
with an empty reason under the campaign's address-space cap; Pillow's warnings on damaged metadata): one
RenderError with the place and a reason, or a clean read without a stray warning."""
from __future__ import annotations

import io
import struct
import warnings
import zlib

import numpy as np
import pytest
from PIL import Image

from mpeg4fa.render.errors import RenderError
from mpeg4fa.render.images import read_image

PIXELS = np.arange(12 * 16 * 3, dtype=np.uint8).reshape(12, 16, 3)


@pytest.fixture(autouse=True)
def _no_stray_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def _saved(fmt: str, **options) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(PIXELS).save(buf, fmt, **options)
    return buf.getvalue()


def test_a_png_chunk_longer_than_the_file_is_refused_from_its_header(tmp_path):
    png = bytearray(_saved("PNG"))
    assert png[37:41] == b"IDAT"
    struct.pack_into(">I", png, 33, 0xFE000000)  # what image:1808@1 held: 4 GB claimed in a small file
    path = tmp_path / "bomb.png"
    path.write_bytes(png)
    for source, where in ((path, str(path)), (bytes(png), "<image bytes>")):
        with pytest.raises(RenderError) as info:
            read_image(source, "texture image")
        text = str(info.value)
        assert text.startswith(f"{where}: cannot read the texture image: damaged or truncated PNG: chunk "
                               f"IDAT at byte 33 claims 4,261,412,864 bytes, but the file has "), text


def test_a_png_cut_inside_a_chunk_says_so_and_a_whole_one_reads():
    png = _saved("PNG")
    with pytest.raises(RenderError, match=r"chunk IDAT at byte 33 claims \d+ bytes, but the file has 10 after"):
        read_image(png[:55], "photo")
    assert (read_image(png, "photo") == PIXELS).all()


def test_memory_running_out_while_decoding_is_one_clear_line(monkeypatch):
    def exhausted(self, *args, **kwargs):
        raise MemoryError()  # what the campaign's 2 GiB cap raised, with no message
    monkeypatch.setattr(Image.Image, "convert", exhausted)
    with pytest.raises(RenderError) as info:
        read_image(_saved("PNG"), "photo")
    assert "too large to decode in the memory available" in str(info.value) and "()" not in str(info.value)


def test_a_decoder_error_without_a_message_still_gives_a_reason(monkeypatch):
    def broken(self, *args, **kwargs):
        raise OSError()
    monkeypatch.setattr(Image.Image, "convert", broken)
    with pytest.raises(RenderError, match=r"damaged or truncated image \(OSError\)"):
        read_image(_saved("PNG"), "photo")


def test_corrupt_exif_in_a_jpeg_is_not_read_and_not_warned():
    """Pillow parses a JPEG's EXIF for its DPI only; a damaged one leaves the pixels alone: silenced."""
    exif = (b"Exif\x00\x00II*\x00\x08\x00\x00\x00" + struct.pack("<H", 1)
            + struct.pack("<HHII", 0x011A, 5, 1, 0xFFF0) + bytes(4))  # XResolution's value far past the data
    assert read_image(_saved("JPEG", exif=exif), "photo").shape == (12, 16, 3)


def test_an_invalid_apng_control_reads_the_default_image_silently():
    png = _saved("PNG")
    apng = png[:33] + _chunk(b"acTL", struct.pack(">II", 0, 0)) + png[33:]  # 0 frames: Pillow warns, then reads
    assert (read_image(apng, "photo") == PIXELS).all()


def test_a_damaged_tiff_directory_is_the_files_fault():
    """A TIFF's tags are its layout: Pillow skipping one (its data past the file's end) is a damaged file."""
    tif = bytearray(_saved("TIFF", description="a description long enough to stand outside the entry"))
    ifd = struct.unpack_from("<I", tif, 4)[0]
    for k in range(struct.unpack_from("<H", tif, ifd)[0]):
        if struct.unpack_from("<H", tif, ifd + 2 + 12 * k)[0] == 270:
            struct.pack_into("<I", tif, ifd + 2 + 12 * k + 4, 0x100000)
    with pytest.raises(RenderError, match=r"damaged TIFF image \(Tag data larger than file. Skipping tag 270\)"):
        read_image(bytes(tif), "photo")
    assert (read_image(_saved("TIFF"), "photo") == PIXELS).all()


def _picture() -> np.ndarray:
    """A 40 x 30 picture no turn or flip leaves alike: a ramp across, another down, a dark corner."""
    y, x = np.mgrid[0:30, 0:40]
    rgb = np.stack([x * 6, y * 8, np.full_like(x, 90)], axis=2).astype(np.uint8)
    rgb[:5, :5] = 0
    return rgb


def test_a_sixteen_bit_grey_png_reads_as_its_eight_bit_self(tmp_path):
    """Fuzz of 2026-12-07: Pillow's own conversion clips 16-bit grey to 255, so a 16-bit photo read almost white
    (mean 245) and every photo command said "no face found"."""
    grey = np.asarray(Image.fromarray(_picture()).convert("L"))
    path = tmp_path / "g16.png"
    Image.fromarray(grey.astype(np.uint16) * 257).save(path)
    with Image.open(path) as written:
        assert written.mode.startswith("I")
    got = read_image(path, "photo")
    assert got.shape == (30, 40, 3) and np.abs(got[:, :, 0].astype(int) - grey).max() <= 1


@pytest.mark.parametrize("orientation, turn", [(3, 2), (6, -1), (8, 1)])
def test_a_photo_stored_sideways_is_read_upright(tmp_path, orientation, turn):
    """Fuzz of 2026-12-07: an EXIF Orientation of 6 (a phone held upright) was ignored, so the face was found lying
    on its side and the FDP's scale came out 0.910 mm per pixel against 0.615 upright. Photos are turned; textures
    are not (the fuzz campaign's check that an FDP texture's header size is its decoded size holds)."""
    upright = _picture()
    stored = np.rot90(upright, -turn)  # what the camera wrote; the tag says how to turn it back
    exif = Image.Exif()
    exif[0x0112] = orientation
    path = tmp_path / "phone.png"
    Image.fromarray(np.ascontiguousarray(stored)).save(path, exif=exif.tobytes())
    assert np.array_equal(read_image(path, "photo", turn=True), upright)
    # a texture is read as stored: its coordinates (an FDP's receiver knows no EXIF) name those pixels
    assert np.array_equal(read_image(path, "texture image"), stored)
