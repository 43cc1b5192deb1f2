"""The site's generated parts say what the pipeline and the benchmarks' JSON say: the layers and bitstream
diagrams (tools/docs_diagrams.py) and the Benchmarks page (tools/docs_benchmarks.py)."""
from __future__ import annotations

import importlib.util
import io
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from mpeg4fa.face import asset

ROOT = Path(__file__).resolve().parents[2]


def _tool(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "tools" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def diagrams():
    return _tool("docs_diagrams")


@pytest.fixture(scope="module")
def bench():
    return _tool("docs_benchmarks")


@pytest.fixture(scope="module")
def said(diagrams):
    return diagrams.spoken()


def test_bit_ruler_tiles_the_stream_and_counts_its_frames(diagrams, said, tmp_path):
    drawn = diagrams.bitstream_picture(said, tmp_path)
    elements, frame_bits = drawn["elements"], drawn["frame_bits"]
    codes = sum(e.width for e in elements if e.frame is None)
    assert codes + sum(frame_bits.values()) == 8 * len(said.bits)  # every bit belongs to a code or a frame
    assert len(frame_bits) == len(said.stream)
    assert drawn["intra"] == set(said.stream.intra)  # the frames drawn as intra are the decoder's
    runs = drawn["runs"]  # the labelled brackets cover the ruler from bit 0 to its end, gapless
    assert runs[0][1] == 0 and runs[-1][2] == drawn["shown_end"]
    assert all(a[2] == b[1] for a, b in zip(runs, runs[1:]))
    image = Image.open(tmp_path / "bitstream.png")
    assert image.width >= 1200 and image.height >= 400


@pytest.mark.skipif(not asset.is_installed(), reason="generic head not built: run `mpeg4fa model install`")
def test_layers_show_one_frame_as_the_face_engine_moves_it(diagrams, said, tmp_path):
    from mpeg4fa.face import FaceModel
    from mpeg4fa.spec import FEATURE_POINTS

    face = FaceModel.default()
    drawn = diagrams.layers_picture(face, said, tmp_path)
    values = drawn["values"]
    assert len(drawn["moving"]) >= 5  # the frame drawn is a speaking one, not a rest
    # the red points are where the FAPs put them: the jaw point 2.1 moved down by open_jaw x MNS0 / 1024
    labels = [p.label for p in FEATURE_POINTS]
    chin = labels.index("2.1")
    moved = drawn["pose"].feature_points[chin] - drawn["neutral"].feature_points[chin]
    assert values[2] > 100
    assert -moved[1] == pytest.approx(values[2] * face.fapu.MNS0 / 1024, rel=1e-6)
    assert drawn["edges"] > 5000
    image = Image.open(tmp_path / "layers.png")
    assert image.width >= 800 and image.height >= 700


def test_committed_diagrams_are_current(tmp_path):
    """The concepts page's pictures show today's pipeline: drawn again, in a fresh process (the speech layer's
    timing can differ by a frame's blend after other languages were spoken in the same process), they carry the
    same figures (PNG text ``mpeg4fa-figures``: the stream's bytes, each frame's bits, the FAP values drawn).
    If this fails, run tools/docs_pictures.py (or tools/dev.sh docs) and commit docs/media."""
    subprocess.run([sys.executable, str(ROOT / "tools" / "docs_diagrams.py"), "--out", str(tmp_path)], check=True,
                   capture_output=True, timeout=300)
    for name in ("bitstream.png", "layers.png"):
        fresh = json.loads(Image.open(tmp_path / name).text["mpeg4fa-figures"])
        committed = json.loads(Image.open(ROOT / "docs" / "media" / name).text["mpeg4fa-figures"])
        assert committed == fresh, f"docs/media/{name} is stale: run tools/docs_pictures.py"


def test_benchmarks_page_states_provenance_or_how_to_measure(bench, tmp_path, monkeypatch):
    monkeypatch.setattr(bench, "TOOLS", tmp_path)
    made = {"machine": "a test machine", "date": "2026-01-02 03:04 UTC", "command": "python tools/bench_codec.py"}
    (tmp_path / "bench_codec.json").write_text(json.dumps(
        {"_made": made, "rows": [{"stream": "a", "frames_per_s": 123456.7}, {"stream": "b", "frames_per_s": 0.5}],
         "deformer_a": {"fps": 10, "setup_s": 0.1}, "deformer_b": {"fps": 20, "setup_s": 0.2}}))
    (tmp_path / "bench_newthing.json").write_text(json.dumps({"x": 1}))
    page = bench.page_markdown(plotted=set())
    assert "Made on a test machine, 2026-01-02 03:04 UTC, by `python tools/bench_codec.py`." in page
    assert "| a | 123,457 |" in page and "| b | 0.5 |" in page  # the JSON's figures, formatted
    assert "| deformer_b | 20 | 0.2 |" in page  # sibling objects with the same fields: one table
    assert "newthing" in page  # a JSON the page does not know yet still shows
    (tmp_path / "bench_render.json").write_text(json.dumps({"against": "/tmp/old", "rounds": 3}))
    pngs = bench.plots()  # a JSON in another form than its plot's: no plot, and the page says why
    assert "render.png" not in pngs and "codec.png" not in pngs
    assert "No plot: `bench_render.json` is not in the form" in bench.page_markdown(plotted=set(pngs))
    for other in bench.BENCHES:
        if other.name not in ("codec", "render"):  # no JSON: a line says how to make it
            needed = "".join(f"{arg} " for arg in other.required)  # e.g. what a timing is compared against
            assert f"`.venv/bin/python tools/{other.script.name} {needed}{other.json_flag} " \
                   f"tools/bench_{other.name}.json`" in page


def test_every_committed_benchmark_json_renders_and_plots(bench):
    page = bench.page_markdown(plotted=set())
    present = sorted((ROOT / "tools").glob("bench_*.json"))
    assert present, "no benchmark JSON committed in tools/"
    assert page.count("Made on ") == len(present)
    pngs = bench.plots()
    page = bench.page_markdown(plotted=set(pngs))
    for name in bench.PLOTS:
        path = ROOT / "tools" / f"bench_{name}.json"
        if not path.is_file():
            continue
        if f"{name}.png" not in pngs:
            # a JSON made by `docs_benchmarks.py --run` has the form its plot was written against: it must draw;
            # one its benchmark rewrote in another form may not, and then the page says why
            assert "_made" not in json.loads(path.read_text()), f"{path.name}: {bench.PLOT_ERRORS.get(name)}"
            assert f"No plot: `{path.name}`" in page
        else:
            image = np.asarray(Image.open(io.BytesIO(pngs[f"{name}.png"])).convert("L"))
            assert (image < 200).mean() > 0.01  # something drawn, not a blank canvas
