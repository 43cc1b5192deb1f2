"""OBJ meshes (--face-mesh) are read within a documented size and a foreign file is named (issue 26 item 4)."""
from __future__ import annotations

import pytest

from mpeg4fa.fdp import FdpError, mesh_from_obj, read_obj
from mpeg4fa.fdp import obj as obj_module


def test_a_foreign_file_named_obj_is_said_as_such(tmp_path):
    path = tmp_path / "face.obj"
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(40))
    with pytest.raises(FdpError, match=r"not an OBJ mesh: starts with 0x89504E47 \(a PNG image\)") as info:
        read_obj(path)
    assert str(info.value).startswith(str(path))


def test_an_oversized_obj_is_refused_before_parsing(tmp_path, monkeypatch):
    monkeypatch.setattr(obj_module, "MAX_OBJ_BYTES", 1000)
    text = "v 0 0 0\nv 1 0 0\nv 0 1 0\n" * 50 + "f 1 2 3\n"  # 1,208 bytes
    path = tmp_path / "big.obj"
    path.write_text(text)
    with pytest.raises(FdpError, match=r"big\.obj: is 1,208 bytes, more than an OBJ mesh may be \(1,000\)"):
        read_obj(path)
    with pytest.raises(FdpError, match="more than the 1,000 read"):
        mesh_from_obj(text, "big.obj")
    assert obj_module.MAX_OBJ_BYTES == 1000 and len(mesh_from_obj(text[:200] + "f 1 2 3\n").vertices) >= 3


def test_image_size_of_a_png_with_two_headers_is_unknown(tmp_path):
    import io
    import struct
    import zlib

    import numpy as np
    from PIL import Image

    from mpeg4fa.fdp.build import image_size

    buf = io.BytesIO()
    Image.fromarray(np.zeros((12, 16, 3), np.uint8)).save(buf, "PNG")
    png = buf.getvalue()
    body = struct.pack(">IIBBBBB", 17, 12, 8, 2, 0, 0, 0)
    extra = struct.pack(">I", 13) + b"IHDR" + body + struct.pack(">I", zlib.crc32(b"IHDR" + body))
    assert image_size(png) == (16, 12)
    assert image_size(png[:8] + extra + png[8:]) is None  # fuzz image:262: 17 from the first, Pillow took 16
