"""The GLB export: structure, morph targets and weights read back from the file, validator, speech, CLI."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from mpeg4fa.decoded import resolve
from mpeg4fa.errors import MpegFaError
from mpeg4fa.export.arkit_units import NoFaceUnitsError, arkit_units, base_unit
from mpeg4fa.export.gltf import MM, PART_LOOK, ExportError, build_glb, export_glb
from mpeg4fa.fba import FapStream
from mpeg4fa.face.deformers.arkit import deform_arkit, unit_weights
from mpeg4fa.formats import write_fap
from mpeg4fa.render.lashes import STRANDS, build_lashes, lash_vertices, strand_image, strand_uv
from mpeg4fa.render.timing import presentation_times

from export.gltf_files import OPEN_FRAME, load, read_accessor, talk_stream, validate, world_positions


@pytest.fixture(scope="module")
def stream():
    return talk_stream()


def _export(tmp_path, stream, face, **options):
    path = tmp_path / "head.glb"
    result = export_glb(stream, face, path, **options)
    return path, result, load(path)


def _primitives(gltf) -> dict:
    """Part -> (mesh index, primitive), across the meshes."""
    return {prim.extras["part"]: (m, prim) for m, mesh in enumerate(gltf.meshes) for prim in mesh.primitives}


def _check_common(gltf, result, stream, face, n_targets):
    prims = _primitives(gltf)
    assert sorted(prims) == sorted(PART_LOOK) and result.n_parts == 7 and result.n_targets == n_targets
    animation, = gltf.animations
    channel = animation.channels[0]
    assert channel.target.path == "weights"
    morphed = gltf.nodes[channel.target.node].mesh
    mesh = gltf.meshes[morphed]
    assert len(mesh.extras["targetNames"]) == len(mesh.weights) == n_targets
    for part, (m, prim) in prims.items():
        assert len(prim.targets or []) == (n_targets if m == morphed else 0)
        position = read_accessor(gltf, prim.attributes.POSITION)
        acc = gltf.accessors[prim.attributes.POSITION]
        assert acc.min == position.min(axis=0).tolist() and acc.max == position.max(axis=0).tolist()
        indices = read_accessor(gltf, prim.indices)
        if part == "lashes":  # cards grown from the lids (render/lashes.py), roots, middles, tips, at rest
            layout = build_lashes(face.mesh)
            assert np.abs(position - lash_vertices(layout, face.mesh.vertices)[:, :3] * MM).max() < 1e-7
            assert np.array_equal(indices, layout.indices.reshape(-1))
            uv, k = read_accessor(gltf, prim.attributes.TEXCOORD_0), len(layout.rows)
            assert np.array_equal(uv[:, 1], np.repeat([1.0, 0.5, 0.0], k))  # roots on the image's bottom row (v down)
            assert np.allclose(uv[:k, 0], uv[2 * k:, 0]) and (np.diff(uv[:k // 4, 0]) > 0).all()  # along the margin
            continue
        assert indices.max() < len(position) and len(indices) == 3 * len(face.mesh.triangles[part])
        # every vertex of the primitive is a vertex of its part, at its rest position
        nearest, _ = cKDTree(face.mesh.vertices[face.mesh.part(part)] * MM).query(position)
        assert nearest.max() < 1e-6
    assert {c.target.path for c in animation.channels} <= {"weights", "rotation", "translation"}
    sampler = animation.samplers[channel.sampler]
    assert all(s.interpolation == "LINEAR" and s.input == sampler.input for s in animation.samplers)
    times = read_accessor(gltf, sampler.input)
    assert np.allclose(times, presentation_times(stream)) and len(times) == result.n_frames == len(stream)
    assert gltf.accessors[sampler.input].min == [float(times[0])] and gltf.accessors[sampler.input].max == [float(times[-1])]
    weights = read_accessor(gltf, sampler.output)
    assert len(weights) == len(times) * n_targets
    return weights.reshape(len(times), n_targets)


def _targets(gltf, part):
    _, prim = _primitives(gltf)[part]
    return np.stack([read_accessor(gltf, t["POSITION"]) for t in prim.targets])


def _rest(gltf, part):
    _, prim = _primitives(gltf)[part]
    return read_accessor(gltf, prim.attributes.POSITION)


def test_morph_targets_are_the_arkit_units_driven_as_the_deformer_drives_them(generic_face, stream, tmp_path):
    path, result, gltf = _export(tmp_path, stream, generic_face, animation="morph")
    names = list(generic_face.mesh.face_units.names)
    assert len(names) == 52
    weights = _check_common(gltf, result, stream, generic_face, 52)
    assert gltf.meshes[0].extras["targetNames"] == names
    values = resolve(stream)
    rig = generic_face.arkit_rig
    driven = unit_weights(rig, values.T).T  # (n, 30) the deformer's own weights
    for d, name in enumerate(rig.unit_names):
        halves = [k for k, other in enumerate(rig.unit_names) if base_unit(other) == base_unit(name)]
        expected = driven[:, halves].mean(axis=1)
        assert np.allclose(weights[:, names.index(base_unit(name))], expected, atol=1e-6), name
    undriven = [u for u, n in enumerate(names) if n not in {base_unit(d) for d in rig.unit_names}]
    assert len(undriven) == 52 - 27 and not weights[:, undriven].any()
    # each unit's lash target: the cards grown from the unit's shape (a viewer blends them linearly: at half a blink
    # they sit 0.2 mm from the cards grown from the half-blinked lids)
    layout, rest = build_lashes(generic_face.mesh), generic_face.mesh.vertices
    at_rest, shapes = lash_vertices(layout, rest)[:, :3], arkit_units(generic_face).shapes
    grown = _targets(gltf, "lashes") / MM
    for name in ("eyeBlinkLeft", "eyeBlinkRight", "jawOpen"):
        u = names.index(name)
        assert np.abs(grown[u] - (lash_vertices(layout, rest + shapes[u])[:, :3] - at_rest)).max() < 1e-3, name
    assert np.abs(grown[names.index("eyeBlinkLeft")]).max() > 3  # the blink swings the lashes by millimetres
    assert weights[OPEN_FRAME, names.index("jawOpen")] > 0.3 and not weights[0].any()
    # the one-sided brow FAP drives the left half only: the unit shows it at half on both sides
    brow = [k for k, n in enumerate(rig.unit_names) if n.startswith("browInnerUp")]
    assert driven[-1, brow].max() > 0 and driven[-1, brow].min() == 0
    # the skin primitive's targets are the driven shapes (halves summed) at its vertices, in metres
    skin = _targets(gltf, "skin")
    units = arkit_units(generic_face)
    position = _rest(gltf, "skin")
    source = _sources(generic_face, position, "skin")
    assert np.allclose(skin, (units.shapes[:, source] * MM).astype(np.float32), atol=1e-7)
    prims = _primitives(gltf)
    assert not _targets(gltf, "teeth_upper").any()  # no unit moves it: all-zero targets without buffer views
    assert all(gltf.accessors[t["POSITION"]].bufferView is None for t in prims["teeth_upper"][1].targets)
    assert prims["eye_l"][0] != 0 and not prims["eye_l"][1].targets  # the eyes turn as nodes of their own
    # the lower teeth ride on jawOpen as the deformer's jaw carries them (a turn: nearly linear in the FAP)
    teeth = _targets(gltf, "teeth_lower")
    moving = {names[u] for u in np.flatnonzero(np.abs(teeth).max(axis=(1, 2)) > 0)}
    assert "jawOpen" in moving and moving <= {"jawOpen", "jawForward", "jawLeft", "jawRight", "tongueOut"}
    rest_teeth = _rest(gltf, "teeth_lower")
    shown = rest_teeth + np.tensordot(weights[OPEN_FRAME], teeth, axes=1)
    posed = deform_arkit(generic_face.rig, rig, values[OPEN_FRAME]).vertices[_sources(generic_face, rest_teeth,
                                                                                       "teeth_lower")] * MM
    drop = np.abs(posed - rest_teeth).max()
    assert drop > 0.004 and np.abs(shown - posed).max() < 0.05 * drop, (drop, np.abs(shown - posed).max())
    # frames without the one-sided brow: the skin is the ARKit deformer's sculpt before its correction
    k = OPEN_FRAME
    sculpt = generic_face.rig.rest[generic_face.mesh.part("skin")] + (rig.deltas @ driven[k]).reshape(-1, 3)
    shown = position + np.tensordot(weights[k], skin, axes=1)
    assert np.abs(shown - sculpt[source] * MM).max() < 1e-6


def _sources(face, position, part):
    """The mesh vertex of each glTF vertex of a part (nearest rest position: they coincide)."""
    span = face.mesh.part(part)
    distance, nearest = cKDTree(face.mesh.vertices[span] * MM).query(position)
    assert distance.max() < 1e-6
    return span.start + nearest


def test_vertex_animation_is_the_face_pose_of_every_frame(procedural_face, stream, tmp_path):
    path, result, gltf = _export(tmp_path, stream, procedural_face, animation="vertex")
    values = resolve(stream)
    distinct = len(np.unique(values, axis=0))
    weights = _check_common(gltf, result, stream, procedural_face, distinct)
    assert np.array_equal(weights.sum(axis=1), np.ones(len(stream))) and set(np.unique(weights)) == {0.0, 1.0}
    for k in (0, OPEN_FRAME, len(stream) - 1):
        pose = procedural_face.pose_values(values[k]).vertices
        for part, shown in world_positions(gltf, k).items():
            if part == "lashes":  # grown from the posed lids as the renderer grows them
                want = lash_vertices(build_lashes(procedural_face.mesh), pose)[:, :3]
                assert np.abs(shown - want * MM).max() < 1e-6, (part, k)
                continue
            source = _sources(procedural_face, _rest(gltf, part), part)
            assert np.abs(shown - pose[source] * MM).max() < 1e-6, (part, k)
    lower = _targets(gltf, "teeth_lower")
    open_target = int(np.argmax(weights[OPEN_FRAME]))
    assert np.abs(lower[open_target]).max() > 0.005  # the jaw drops the lower teeth by millimetres
    names = gltf.meshes[0].extras["targetNames"]
    assert names[int(np.argmax(weights[0]))] == "frame 0"


def test_lashes_close_with_the_lids_and_wear_their_strands(procedural_face, tmp_path):
    import io

    from PIL import Image

    s = FapStream.empty(3)
    s.source_fps = 25.0
    s.timestamps[:] = np.arange(3) / 25.0
    s.fap_mask[:, [18, 19]] = True
    s.fap_values[:, 18] = s.fap_values[:, 19] = [0, 500, 1000]  # both upper lids: open, half, shut
    path, _, gltf = _export(tmp_path, s, procedural_face, animation="vertex")
    layout = build_lashes(procedural_face.mesh)
    values = resolve(s)
    tips = slice(2 * len(layout.rows), None)
    moved = []
    for k in range(3):
        shown = world_positions(gltf, k)["lashes"]
        want = lash_vertices(layout, procedural_face.pose_values(values[k]).vertices)[:, :3] * MM
        assert np.abs(shown - want).max() < 1e-6, k
        moved.append(np.linalg.norm(shown[tips] - world_positions(gltf, 0)["lashes"][tips], axis=1).max() / MM)
    assert moved[0] == 0 and 2 < moved[1] < moved[2], moved  # the upper lashes' tips swing down by millimetres
    _, prim = _primitives(gltf)["lashes"]
    material = gltf.materials[prim.material]
    assert material.alphaMode == "MASK" and material.doubleSided and 0 < material.alphaCutoff < 0.5
    texture = gltf.textures[material.pbrMetallicRoughness.baseColorTexture.index]
    assert gltf.samplers[texture.sampler].wrapS == 10497  # REPEAT: the strands run on along the margin
    view = gltf.bufferViews[gltf.images[texture.source].bufferView]
    rgba = np.asarray(Image.open(io.BytesIO(gltf.binary_blob()[view.byteOffset:view.byteOffset + view.byteLength])))
    alpha = rgba[..., 3].astype(float) / 255
    assert rgba.shape[2] == 4 and rgba[..., :3].max() < 80  # dark strands
    assert alpha[-1].mean() > 0.6 and alpha[0].mean() < 0.1  # dense at the roots (bottom row), few reach the top


def test_a_margin_wears_its_strands_once(generic_face):
    """Each lid margin of the generic head spans less than one repeat of the strand image along u, so no strand shows
    twice along a lid (at 64 strands the upper lids' last 8 mm wore their first 8 mm's strands); the image does not
    repeat within itself."""
    layout = build_lashes(generic_face.mesh)
    u = strand_uv(layout)[:len(layout.rows), 0]
    margin = np.floor(layout.static[:len(layout.rows), 5] / 100.0)  # the margins are laid 100 mm apart along u
    spans = [np.ptp(u[margin == m]) for m in np.unique(margin)]
    assert len(spans) == 4 and max(spans) < 1, spans
    image = strand_image()
    assert image.shape[1] == 16 * STRANDS
    for period in (STRANDS // 4, STRANDS // 2):  # the strands at k and k + period are not the same strands
        shift = image.shape[1] * period // STRANDS
        assert np.abs(image[:, :shift].astype(int) - image[:, shift:2 * shift]).mean() > 10, period


def test_morph_animation_needs_face_units(procedural_face, stream, tmp_path):
    with pytest.raises(NoFaceUnitsError, match="no ARKit face units") as err:
        export_glb(stream, procedural_face, tmp_path / "head.glb")
    assert "--animation vertex" in err.value.hint
    assert not list(tmp_path.iterdir())


def test_validator_finds_no_errors(face, stream, tmp_path):
    """Morph animation on the generic head (vertex on both), and an embedded texture (given, or the skin's colours
    baked): 0 errors, 0 warnings."""
    texture = np.zeros((64, 64, 3), np.uint8)
    texture[..., 0] = np.arange(64)[:, None] * 4
    animations = ("vertex", "morph") if face.mesh.face_units is not None else ("vertex",)
    for animation in animations:
        path = tmp_path / f"{animation}.glb"
        export_glb(stream, face, path, animation=animation, texture=texture if animation == "vertex" else None)
        report = validate(path)
        issues = report["issues"]
        assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"][:5]
        info = report["info"]
        lashes = animation != "vertex"  # a photo texture has its own lashes: the cards are left out
        assert info["hasMorphTargets"] and info["animationCount"] == 1 and info["drawCallCount"] == 6 + lashes
        assert info["hasTextures"]  # the given texture, or the skin's own colours baked (brows and lips)


def test_texture_is_embedded_png_on_the_skin(procedural_face, stream, tmp_path):
    import io

    from PIL import Image
    texture = np.random.default_rng(1).integers(0, 255, (32, 48, 3), dtype=np.uint8)
    path, _, gltf = _export(tmp_path, stream, procedural_face, animation="vertex", texture=texture)
    image, eye = gltf.images  # the photo (the teeth's and tongue's islands baked on it), the eyeball's own bake
    assert "lashes" not in _primitives(gltf)  # a photo has the person's own lashes, as the renderer leaves them out
    view = gltf.bufferViews[image.bufferView]
    png = gltf.binary_blob()[view.byteOffset:view.byteOffset + view.byteLength]
    got = np.asarray(Image.open(io.BytesIO(png)))
    from mpeg4fa.render import Renderer

    with Renderer(procedural_face, width=48, height=32, lighting=False, lashes=False) as r:
        baked = r.albedo()
    kept = np.isin(baked.owner, [0, 255])  # the skin's texels and those of no island: the photo's own
    assert image.mimeType == "image/png" and eye.name == "eye" and kept.mean() > 0.5
    assert got.shape == texture.shape and np.array_equal(got[kept], texture[kept])
    skin = _primitives(gltf)["skin"][1]
    assert gltf.materials[skin.material].pbrMetallicRoughness.baseColorTexture.index == 0
    uv = read_accessor(gltf, skin.attributes.TEXCOORD_0)
    assert uv.min() >= 0 and uv.max() <= 1
    with pytest.raises(ExportError, match="uint8"):
        build_glb(stream, procedural_face, animation="vertex", texture=texture.astype(np.float32))


def test_speech_is_written_beside_the_glb(procedural_face, stream, tmp_path):
    wav = tmp_path / "speech.wav"
    wav.write_bytes(_tiny_wav())
    path, result, _ = _export(tmp_path, stream, procedural_face, animation="vertex", audio=wav)
    assert result.audio == tmp_path / "head.wav" and (tmp_path / "head.wav").read_bytes() == wav.read_bytes()
    # already beside the GLB under its name: left as it is
    result = export_glb(stream, procedural_face, tmp_path / "speech.glb", animation="vertex", audio=wav)
    assert result.audio == wav
    bad = tmp_path / "noise.wav"
    bad.write_bytes(b"ID3 not a wav file")
    with pytest.raises(ExportError, match="not a WAV"):
        export_glb(stream, procedural_face, tmp_path / "other.glb", animation="vertex", audio=bad)
    assert not (tmp_path / "other.glb").exists() and not (tmp_path / "other.wav").exists()


def _tiny_wav() -> bytes:
    import io
    import wave
    out = io.BytesIO()
    with wave.open(out, "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(16000)
        w.writeframes(np.zeros(1600, np.int16).tobytes())
    return out.getvalue()


def test_empty_stream_is_refused(procedural_face, tmp_path):
    from mpeg4fa.fba.stream import FapStream
    with pytest.raises(ExportError, match="no frames"):
        export_glb(FapStream.empty(0), procedural_face, tmp_path / "x.glb", animation="vertex")


def test_cli_export(cli, generic_face, stream, tmp_path):
    fap = tmp_path / "talk.fap"
    write_fap(stream, fap)
    (tmp_path / "talk.wav").write_bytes(_tiny_wav())
    code, out, err = cli("export", fap, "-o", tmp_path / "talk.glb")
    assert code == 0, err
    assert "52 morph targets" in out and "found beside the stream" in err
    assert load(tmp_path / "talk.glb").meshes[0].extras["targetNames"] == list(generic_face.mesh.face_units.names)
    assert not (tmp_path / "talk.glb.wav").exists()
    code, out, err = cli("export", fap, "--no-audio", "--animation", "vertex", "-o", tmp_path / "v.glb")
    assert code == 0 and "vertex animation" in out and not (tmp_path / "v.wav").exists()


@pytest.mark.parametrize("argv, said", [
    (["-o", "x.obj"], "no export format for suffix '.obj'"),
    (["-o", "x.glb", "--deformer", "muscle"], "--deformer muscle goes with --animation vertex"),
    (["-o", "x.glb", "--format", "azure-json"], "names a glb file, but --format azure-json"),  # fuzz, 2026-12-07
])
def test_cli_usage_errors(cli, stream, tmp_path, argv, said):
    fap = tmp_path / "talk.fap"
    write_fap(stream, fap)
    code, out, err = cli("export", fap, *[str(tmp_path / a) if a.startswith("x.") else a for a in argv])
    assert code == 2 and said in err and "Traceback" not in err


def test_cli_refuses_to_overwrite_the_stream(cli, stream, tmp_path):
    fap = tmp_path / "talk.fap"
    write_fap(stream, fap)
    code, _, err = cli("export", fap, "-o", fap, "--format", "glb")
    assert code == 2 and "would be overwritten" in err
    assert isinstance(NoFaceUnitsError("x"), MpegFaError)


def test_head_and_eye_turns_are_node_rotations(generic_face, tmp_path):
    """FAPs 48-50 (head) and 23-28 (eyeballs) in morph animation: rotation and translation channels on pivot
    nodes; the eyes land where the ARKit deformer puts them, the face turns as the deformer turns it."""
    stream = talk_stream()
    ramp = np.linspace(0, 1, len(stream))
    for fap, peak in ((48, 40000), (49, -60000), (50, 20000),  # head pitch, yaw, roll in 1e-5 rad
                      (23, 30000), (24, 30000), (25, -15000), (26, -15000), (27, 300)):  # eyes; left thrust
        stream.fap_mask[:, fap - 1] = True
        stream.fap_values[:, fap - 1] = np.round(peak * ramp)
    path, result, gltf = _export(tmp_path, stream, generic_face, animation="morph")
    assert validate(path)["issues"]["numErrors"] == 0
    head = gltf.nodes[0]
    assert np.allclose(head.translation, generic_face.mesh.fp("7.1") * MM) and head.children[0] == 1
    animation, = gltf.animations
    paths = sorted((c.target.node, c.target.path) for c in animation.channels)
    eye_pivots = head.children[1:]
    assert paths == sorted([(1, "weights"), (0, "rotation")] + [(n, "rotation") for n in eye_pivots]
                           + [(eye_pivots[0], "translation")])
    for channel in animation.channels:
        if channel.target.path == "rotation":
            quats = read_accessor(gltf, animation.samplers[channel.sampler].output)
            assert quats.shape == (len(stream), 4) and np.allclose(np.linalg.norm(quats, axis=1), 1, atol=1e-6)
            assert np.all(np.einsum("ij,ij->i", quats[1:], quats[:-1]) > 0)
    values = resolve(stream)
    rig = generic_face.arkit_rig
    for k in (0, OPEN_FRAME, len(stream) - 1):
        shown = world_positions(gltf, k)
        posed = deform_arkit(generic_face.rig, rig, values[k]).vertices
        for eye in ("eye_l", "eye_r"):
            source = _sources(generic_face, _rest(gltf, eye), eye)
            assert np.abs(shown[eye] - posed[source] * MM).max() < 1e-6, (eye, k)
        # the face: the unturned morph result turned about 7.1 as the deformer turns it (away from the neck)
        unturned = values[k].copy()
        unturned[47:50] = 0
        flat = deform_arkit(generic_face.rig, rig, unturned).vertices
        skin = _sources(generic_face, _rest(gltf, "skin"), "skin")
        nose = np.flatnonzero(skin == generic_face.mesh.fp_vertex[generic_face.mesh.fp_index("9.3")])[0]
        centre = generic_face.mesh.fp("7.1")
        turn = posed[skin[nose]] - flat[skin[nose]]  # what the turn does to the nose tip in the deformer
        moved = shown["skin"][nose] / MM - _rest(gltf, "skin")[nose] / MM - (
            flat[skin[nose]] - generic_face.mesh.vertices[skin[nose]])
        assert np.abs(moved - turn).max() < 1.0, (k, moved, turn)  # mm; the morph lacks the skin correction
    assert np.abs(turn).max() > 20 and centre[1] > 0


def test_blink_is_the_deformers_lid_turn(generic_face, tmp_path):
    """FAP 19 (close_t_l_eyelid) weighs eyeBlinkLeft (value over one IRISD0); at weight 1 the target puts the skin
    where the ARKit deformer turns the lid over the eyeball."""
    from mpeg4fa.export.arkit_units import LID_SHUT

    stream = talk_stream()
    stream.fap_mask[:, 18] = True
    stream.fap_values[:, 18] = np.round(np.linspace(0, 1.25 * LID_SHUT, len(stream)))
    path, result, gltf = _export(tmp_path, stream, generic_face, animation="morph")
    names = gltf.meshes[0].extras["targetNames"]
    weights = read_accessor(gltf, gltf.animations[0].samplers[0].output).reshape(len(stream), -1)
    values = resolve(stream)
    blink = weights[:, names.index("eyeBlinkLeft")]
    assert np.allclose(blink, np.clip(values[:, 18] / LID_SHUT, 0, 1), atol=1e-6) and blink[-1] == 1.0
    assert not weights[:, names.index("eyeBlinkRight")].any()
    skin = _targets(gltf, "skin")[names.index("eyeBlinkLeft")]
    position = _rest(gltf, "skin")
    source = _sources(generic_face, position, "skin")
    shut = np.zeros(68)
    shut[18] = LID_SHUT
    rig = generic_face.arkit_rig
    lid = deform_arkit(generic_face.rig, rig, shut).vertices[source] * MM
    assert np.abs(position + skin - lid).max() < 1e-6
    upper_lid = generic_face.mesh.fp("3.1") * MM
    moved = np.linalg.norm(skin, axis=1) > 1e-4
    assert moved.any() and np.all(position[moved, 0] > 0)  # the left lid (+x) only
    assert np.linalg.norm(position[moved] - upper_lid, axis=1).max() < 0.03



def test_the_skin_wears_its_baked_colours(face, stream, tmp_path, monkeypatch):
    """Without a texture the head's own colours (brows, lips, the teeth's and tongue's shadow) go in as its texture,
    and the eyeball's (iris and pupil) as theirs, the vertex colours white; where no GL context can be made, the
    lips and the mouth's dark go into the vertex colours instead."""
    import pygltflib

    from mpeg4fa.render import Renderer
    from mpeg4fa.render.errors import RenderError

    path, result, gltf = _export(tmp_path, stream, face, animation="vertex")
    skin = next(p for m in gltf.meshes for p in m.primitives if p.extras["part"] == "skin")
    teeth = ["teeth"] if face.mesh.face_units is not None else []  # the generic head's map keeps the teeth apart
    assert [i.name for i in gltf.images] == ["head", "eye", *teeth, "lashes"]
    eye_sampler = gltf.samplers[gltf.textures[1].sampler]  # no mipmaps: the pole's fan and seam streaked the iris
    assert eye_sampler.minFilter == pygltflib.LINEAR
    assert gltf.materials[skin.material].pbrMetallicRoughness.baseColorTexture is not None
    assert skin.attributes.TEXCOORD_0 is not None
    worn = {p.extras["part"] for m in gltf.meshes for p in m.primitives
            if gltf.materials[p.material].pbrMetallicRoughness.baseColorTexture is not None}
    for m in gltf.meshes:  # a part wears the image with its texture coordinates, or neither
        for p in m.primitives:
            assert (p.extras["part"] in worn) == (p.attributes.TEXCOORD_0 is not None), p.extras["part"]
    assert {"skin", "eye_l", "eye_r"} <= worn  # the eyeballs wear the left one's bake (iris with its detail)
    if face.mesh.face_units is not None:  # the generic head's map keeps its teeth and tongue apart: baked too
        assert worn == {"skin", "teeth_upper", "teeth_lower", "tongue", "eye_l", "eye_r", "lashes"}, worn

    def no_gl(self):
        raise RenderError("cannot create a headless OpenGL context", where="GL context")

    monkeypatch.setattr(Renderer, "albedo", no_gl)
    data, summary = build_glb(stream, face, animation="vertex")
    assert summary["skin"] == "colours" and [i.name for i in pygltflib.GLTF2.load_from_bytes(data).images] == ["lashes"]
    assert result.skin == "albedo"


def test_the_teeth_wear_an_image_of_their_own(generic_face, stream):
    """The teeth's gaps, gums and back teeth's shadow in an image of their own over their islands' box (in the head's
    2048 image a tooth had about a texel a mm, so a gap between two was a texel): a median 8.6-9.4 texels a mm."""
    import io

    from PIL import Image

    data, _ = build_glb(stream, generic_face, animation="vertex")
    gltf = pygltflib_load(data)
    prims = _primitives(gltf)
    for part in ("teeth_upper", "teeth_lower"):
        _, prim = prims[part]
        texture = gltf.materials[prim.material].pbrMetallicRoughness.baseColorTexture
        image = gltf.images[gltf.textures[texture.index].source]
        assert image.name == "teeth"
        view = gltf.bufferViews[image.bufferView]
        size = np.asarray(Image.open(io.BytesIO(gltf.binary_blob()[view.byteOffset:view.byteOffset +
                                                                      view.byteLength]))).shape[:2]
        uv = read_accessor(gltf, prim.attributes.TEXCOORD_0)
        position = read_accessor(gltf, prim.attributes.POSITION) / MM
        tris = read_accessor(gltf, prim.indices).reshape(-1, 3)
        texels = np.linalg.norm((uv[tris[:, 1]] - uv[tris[:, 0]]) * size[::-1], axis=1)
        mm = np.linalg.norm(position[tris[:, 1]] - position[tris[:, 0]], axis=1)
        assert 0.0 <= uv.min() and uv.max() <= 1.0
        assert np.median(texels / np.maximum(mm, 1e-9)) > 8.0, part


def test_the_teeth_s_own_image_lies_on_them(generic_face):
    """The teeth's own image holds, at each tooth triangle's texture coordinates mapped into its frame, what the
    head's image holds at the original ones (measured: mean difference 0.7 upper, 4.5 lower of 255; with the image
    upside down 21 and 26)."""
    from mpeg4fa.render import Renderer
    from mpeg4fa.render.materials import PART_MATERIAL
    from mpeg4fa.render.scene import build_layout

    with Renderer(generic_face, width=2048, height=2048, lighting=False, lashes=False) as r:
        baked = r.albedo()
    layout = build_layout(generic_face.mesh)
    lo, span = np.array(baked.teeth_frame[:2]), np.array(baked.teeth_frame[2:])

    def sample(image: np.ndarray, uv: np.ndarray) -> np.ndarray:  # row 0 = v 1, as the images are
        h, w = image.shape[:2]
        x = np.clip((uv[:, 0] * w).astype(int), 0, w - 1)
        y = np.clip(((1.0 - uv[:, 1]) * h).astype(int), 0, h - 1)
        return image[y, x].astype(int)

    start = 0
    for part in PART_MATERIAL:  # build_layout's order of the parts' triangles
        count = len(generic_face.mesh.triangles.get(part, ()))
        if part.startswith("teeth"):
            uv = layout.uv[layout.indices[start:start + count]].mean(axis=1)
            head, own = sample(baked.image, uv), sample(baked.teeth, (uv - lo) / span)
            flipped = sample(baked.teeth, np.c_[(uv - lo)[:, 0] / span[0], 1.0 - (uv - lo)[:, 1] / span[1]])
            assert np.abs(head - own).mean() < 10.0 < np.abs(head - flipped).mean(), part
        start += count


def pygltflib_load(data: bytes):
    import pygltflib

    return pygltflib.GLTF2.load_from_bytes(data)


def test_a_photo_texture_carries_the_baked_teeth_and_tongue(generic_face, stream):
    """With a photo texture (an FDP's) the teeth and tongue still wear their own baked colours, laid on their islands
    of the photo's image, and the eyeballs theirs: a calibrated head in the browser pages showed white fangs."""
    import io

    import pygltflib
    from PIL import Image

    photo = np.zeros((512, 512, 3), np.uint8)
    photo[..., 1] = 200
    data, summary = build_glb(stream, generic_face, animation="vertex", texture=photo)
    gltf = pygltflib.GLTF2.load_from_bytes(data)
    assert summary["skin"] == "photo" and [i.name for i in gltf.images] == ["head", "eye", "teeth"]
    worn = {p.extras["part"] for m in gltf.meshes for p in m.primitives if p.attributes.TEXCOORD_0 is not None}
    assert worn == {"skin", "teeth_upper", "teeth_lower", "tongue", "eye_l", "eye_r"}, worn
    view = gltf.bufferViews[gltf.images[0].bufferView]
    got = np.asarray(Image.open(io.BytesIO(gltf.binary_blob()[view.byteOffset:view.byteOffset + view.byteLength])))
    changed = (got != photo).any(axis=2)
    assert 0.001 < changed.mean() < 0.05, changed.mean()  # the islands only (measured 0.25 %)
