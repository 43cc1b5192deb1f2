"""Batch rendering on Dask: a local cluster of 2 worker processes renders short streams made here.

One cluster serves the module (started as a user's would be, then reached by its address, the
``--scheduler`` path); the CLI test also starts the default local cluster. The face is the
procedural head's skin given as ``face_mesh``/``face_points``, so nothing needs the generic head.
"""
from __future__ import annotations

import json
import logging
import os
import shutil
from pathlib import Path

import pytest

from mpeg4fa.atomic import PARTIAL_MARK
from mpeg4fa.batch import SUMMARY_NAME, BatchError, load_manifest, run_batch
from mpeg4fa.batch import run as batch_run
from mpeg4fa.render.video import probe_media
from workload import write_face, write_fdp, write_stream, write_tone

SIZE = "160x160"
SECONDS = 1.0


@pytest.fixture(scope="module")
def scheduler():
    """The address of a running local cluster: 2 worker processes, one thread each."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                      scheduler_kwargs={"dashboard_address": "127.0.0.1:0"}, silence_logs=logging.ERROR,
                      env={"LP_NUM_THREADS": "1"}) as cluster:
        yield cluster.scheduler_address


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("batch-inputs")
    obj, points = write_face(folder)
    for i in range(4):
        write_stream(folder / f"s{i}.fba", SECONDS, phase=i)
    write_tone(folder / "s0.wav", SECONDS)
    write_fdp(folder / "wide.fdp", points, obj)
    (folder / "bad.fba").write_bytes(b"\x00\x00\x01\xb0" + b"not a stream" * 20)
    (folder / "noise.wav").write_bytes(b"RIFF\x10\x00\x00\x00WAVEjunk" * 4)
    return folder


def manifest(folder: Path, jobs: list[dict], name: str = "jobs.json") -> Path:
    path = folder / name
    defaults = {"size": SIZE, "face_mesh": "head.obj", "face_points": "points.json"}
    path.write_text(json.dumps({"defaults": defaults, "jobs": jobs}, indent=2))
    return path


def leftovers(out: Path) -> list[str]:
    return sorted(p.name for p in out.rglob("*") if PARTIAL_MARK in p.name)


def frames(path: Path) -> list[bytes]:
    import av

    with av.open(str(path)) as container:
        return [f.to_ndarray(format="rgb24").tobytes() for f in container.decode(video=0)]


def by_output(summary) -> dict:
    return {j.output: j for j in summary.jobs}


GOOD = [{"stream": "s0.fba", "audio": "s0.wav"}, {"stream": "s1.fba", "fdp": "wide.fdp"},
        {"stream": "s2.fba"}, {"stream": "s3.fba", "output": "sub/three.mp4"}]


def test_renders_on_two_workers_resumes_and_renders_only_what_changed(inputs, scheduler, tmp_path):
    jobs = GOOD + [{"stream": "bad.fba"}]
    out = tmp_path / "out"
    first = run_batch(manifest(inputs, jobs), out, scheduler=scheduler)
    assert [j.status for j in first.jobs] == ["rendered"] * 4 + ["failed"]
    done = by_output(first)
    # the bad job failed alone, said why and where, and left nothing behind
    assert "bad.fba" in done["bad.mp4"].error and "fba_object_start_code" in done["bad.mp4"].error
    assert not (out / "bad.mp4").exists() and leftovers(out) == []
    # both workers took jobs; a worker reused its renderer for a job with the same face and options
    assert len({j.worker for j in first.jobs if j.status == "rendered"}) == 2
    assert sum(bool(j.renderer_reused) for j in first.jobs) >= 1
    talk, silent = probe_media(out / "s0.mp4"), probe_media(out / "sub" / "three.mp4")
    assert talk.n_frames == 25 and talk.width == 160 and talk.audio_duration == pytest.approx(SECONDS, abs=0.05)
    assert silent.n_frames == 25 and silent.audio_duration is None
    assert json.loads((out / SUMMARY_NAME).read_text()) == json.loads(json.dumps(first.as_dict()))

    stamps = {p: p.stat().st_mtime_ns for p in out.rglob("*.mp4")}
    again = run_batch(manifest(inputs, jobs), out, scheduler=scheduler)
    assert [j.status for j in again.jobs] == ["skipped"] * 4 + ["failed"]
    assert [j.frames for j in again.jobs[:4]] == [25] * 4
    assert {p: p.stat().st_mtime_ns for p in out.rglob("*.mp4")} == stamps

    killed = [out / ".s2.partial-0123abcd.mp4", out / "..s2.mp4.batch.partial-4567cdef.json"]
    for path in killed:  # what a worker killed in the middle of s2 would leave
        path.write_bytes(b"half")
    write_stream(inputs / "s2.fba", SECONDS, phase=2.5)  # new bytes for s2; a new option for s3
    changed = [*GOOD[:3], {**GOOD[3], "crf": 30}]
    third = run_batch(manifest(inputs, changed), out, scheduler=scheduler)
    assert [j.status for j in third.jobs] == ["skipped", "skipped", "rendered", "rendered"]
    assert (out / "s0.mp4").stat().st_mtime_ns == stamps[out / "s0.mp4"]
    assert (out / "s2.mp4").stat().st_mtime_ns != stamps[out / "s2.mp4"]
    assert leftovers(out) == []

    # a hand-replaced output is not complete any more; nothing left to render starts no cluster
    (out / "s1.mp4").write_bytes(b"not the video")
    fourth = run_batch(manifest(inputs, changed), out, scheduler=scheduler)
    assert [j.status for j in fourth.jobs] == ["skipped", "rendered", "skipped", "skipped"]
    fifth = run_batch(manifest(inputs, changed), out, scheduler="tcp://127.0.0.1:9")  # unreachable: not needed
    assert fifth.count("skipped") == 4 and fifth.workers == 0
    forced = run_batch(manifest(inputs, changed[2:3]), out, scheduler=scheduler, force=True)
    assert [j.status for j in forced.jobs] == ["rendered"]


def test_failed_jobs_leave_no_output_and_stop_no_other(inputs, scheduler, tmp_path):
    write_tone(inputs / "long.wav", SECONDS + 0.5)
    jobs = [{"stream": "s3.fba", "audio": "noise.wav"}, {"stream": "s2.fba", "output": "fine.mp4", "audio": "long.wav"},
            {"stream": "s1.fba", "texture": "points.json", "output": "textured.mp4"}]
    out = tmp_path / "out"
    summary = run_batch(manifest(inputs, jobs), out, scheduler=scheduler)
    done = by_output(summary)
    assert [j.status for j in summary.jobs] == ["failed", "rendered", "failed"]
    assert "noise.wav" in done["s3.mp4"].error
    assert len(done["fine.mp4"].warnings) == 1 and "video padded with 13 frames" in done["fine.mp4"].warnings[0]
    assert "texture" in done["textured.mp4"].error and "points.json" in done["textured.mp4"].error
    assert sorted(p.name for p in out.iterdir()) == [".fine.mp4.batch.json", SUMMARY_NAME, "fine.mp4"]


def test_an_output_a_link_leads_out_of_the_folder_is_not_written_through(inputs, scheduler, tmp_path):
    """Fuzz of 2026-12-07: with ``OUT/s2.mp4`` already a link to a file outside OUT, the batch wrote the video
    through it (the manifest's names are kept inside OUT; what they resolve to now is too)."""
    out, outside = tmp_path / "out", tmp_path / "elsewhere.mp4"
    out.mkdir()
    (out / "s2.mp4").symlink_to(outside)
    summary = run_batch(manifest(inputs, [{"stream": "s2.fba"}, {"stream": "s1.fba"}]), out, scheduler=scheduler)
    done = by_output(summary)
    assert done["s2.mp4"].status == "failed" and "outside the output folder" in done["s2.mp4"].error
    assert done["s1.mp4"].status == "rendered" and not outside.exists() and leftovers(out) == []


def test_manifest_faults_are_all_located_at_once(inputs):
    path = inputs / "faulty.json"
    path.write_text('{"jobs": [\n'
                    '  {"stream": "missing.fba"},\n'
                    '  {"stream": "s1.fba", "sise": 160},\n'
                    '  {"stream": "s2.fba",\n'
                    '   "audio": "gone.wav", "size": "161x160"},\n'
                    '  {"stream": "s3.fba", "output": "s0.mp4"},\n'
                    '  {"stream": "s3.fba", "output": "../up.mp4"},\n'
                    '  {"stream": "s3.fba", "output": "x.avi", "fit": "stretch"},\n'
                    '  {"stream": "s0.fba"}\n'
                    ']}\n')
    with pytest.raises(BatchError) as caught:
        load_manifest(path)
    problems = caught.value.problems
    assert problems == (
        "job 0 at line 2: no such stream file missing.fba",
        "job 1 at line 3: unknown key 'sise' (did you mean 'size'?)",
        "job 2 at line 4: no such audio file gone.wav",
        "job 2 at line 4: size: 161x160 is odd; an MP4 (H.264) needs even sizes, e.g. 162x160",
        "job 4 at line 7: output '../up.mp4' must be a name under the output folder (no absolute path, no '..', "
        "not hidden)",
        "job 5 at line 8: fit: 'stretch' is not one of pad, trim",
        "job 5 at line 8: output 'x.avi' is not a video name: end it in .mp4, .m4v, .mov",
        "job 6 at line 9: output s0.mp4 is also the output of job 3 at line 6",
    ), problems
    assert caught.value.where == str(path)

    path.write_text('[{"stream": "s1.fba"},\n {"stream": "s2.fba",}]')
    with pytest.raises(BatchError, match="invalid JSON") as caught:
        load_manifest(path)
    assert caught.value.where == f"{path}:2:22"

    csv_path = inputs / "faulty.csv"
    csv_path.write_text("stream,audio,size\ns0.fba,s0.wav,160\ns1.fba,nothing.wav,\n\ns2.fba,,96x96x2\n")
    with pytest.raises(BatchError) as caught:
        load_manifest(csv_path)
    assert caught.value.problems[0] == "job 1 at line 3: no such audio file nothing.wav"
    assert caught.value.problems[1].startswith("job 2 at line 5: size: '96x96x2': expected W or WxH")
    csv_path.write_text("stream,colour\ns0.fba,red\n")
    with pytest.raises(BatchError, match="unknown column 'colour'"):
        load_manifest(csv_path)


def test_manifest_values_are_read_as_play_reads_its_options(inputs):
    path = inputs / "nested.json"
    path.write_text(json.dumps({"defaults": {"crf": "23"}, "jobs": [
        {"stream": "s0.fba", "options": {"size": [96, 64], "view": "left", "fdp_texture": "no", "fps": 50}},
        {"stream": "s1.fba", "audio": "s0.wav", "output": "b/one.mov", "size": 128, "aa": 4, "deformer": "blocks",
         "blocks": "lip_t,lip_b"}]}))
    first, second = load_manifest(path).jobs
    assert first.output == "s0.mp4" and first.stream == inputs / "s0.fba" and first.audio is None
    assert first.options["size"] == (96, 64) and first.options["view"] == "left" and first.options["crf"] == 23
    assert first.options["fdp_texture"] is False and first.options["fps"] == 50.0 and first.options["fit"] == "pad"
    assert second.output == "b/one.mov" and second.audio == inputs / "s0.wav" and second.options["size"] == (128, 128)
    assert second.options["blocks"] == ("lip_t", "lip_b") and second.options["aa"] == 4
    path.write_text(json.dumps([{"stream": "s0.fba", "view": "left", "options": {"view": "right"}},
                                {"stream": "s1.fba", "blocks": "lip_t"},
                                {"stream": "s2.fba", "face_mesh": "head.obj"}]))
    with pytest.raises(BatchError) as caught:
        load_manifest(path)
    assert caught.value.problems == (
        "job 0 at line 1: 'view' is given both in the job and in its options",
        "job 1 at line 1: blocks goes with deformer blocks, not fap",
        "job 2 at line 1: face_mesh and face_points go together (an OBJ and its feature points, JSON label -> "
        "vertex index or [x, y, z])")


def test_an_output_may_not_overwrite_an_input(inputs, tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    shutil.copy(inputs / "s0.fba", folder / "talk.fba")
    (folder / "talk.mp4").write_bytes(b"x")  # an input named like an output
    path = folder / "jobs.json"
    path.write_text(json.dumps([{"stream": "talk.fba", "texture": "talk.mp4"}]))
    with pytest.raises(BatchError, match="would overwrite an input: job 0 at line 1: output talk.mp4 is the texture"):
        run_batch(path, folder)
    assert (folder / "talk.mp4").read_bytes() == b"x"


def test_an_unreachable_scheduler_is_one_error(inputs, tmp_path, monkeypatch):
    monkeypatch.setattr(batch_run, "CONNECT_TIMEOUT_S", 1)
    with pytest.raises(BatchError, match="cannot reach the Dask scheduler") as caught:
        run_batch(manifest(inputs, GOOD[2:3], "one.json"), tmp_path / "out", scheduler="tcp://127.0.0.1:9")
    assert caught.value.where == "tcp://127.0.0.1:9"


def test_cli(cli, capsys, inputs, scheduler, tmp_path):
    with pytest.raises(SystemExit) as caught:
        cli("batch", "--help")
    assert caught.value.code == 0 and "--scheduler ADDRESS" in capsys.readouterr().out
    out = tmp_path / "videos"
    csv_path = inputs / "jobs.csv"
    csv_path.write_text("stream,output,size,face_mesh,face_points\n"
                        f"s2.fba,two.mp4,{SIZE},head.obj,points.json\n"
                        f"bad.fba,bad.mp4,{SIZE},head.obj,points.json\n")
    code, stdout, stderr = cli("batch", csv_path, "-o", out, "--scheduler", scheduler, "--json")
    assert code == 1
    summary = json.loads(stdout)
    assert summary["counts"] == {"rendered": 1, "skipped": 0, "failed": 1} and summary["scheduler"] == scheduler
    assert summary["jobs"][0]["frames"] == 25 and os.path.isfile(out / "two.mp4") and leftovers(out) == []
    assert stderr.count("\n") == 1 and stderr.startswith("mpeg4fa batch: error: bad.mp4 (job 1 at line 3): ")
    # the pixels `mpeg4fa play` gives with the same options
    code, _, stderr = cli("play", inputs / "s2.fba", "--face-mesh", inputs / "head.obj", "--face-points",
                          inputs / "points.json", "--size", SIZE, "--no-audio", "-o", tmp_path / "played.mp4")
    assert code == 0, stderr
    assert frames(out / "two.mp4") == frames(tmp_path / "played.mp4")
    # the default: a local cluster made for the run (only the bad job is left to do)
    code, stdout, stderr = cli("batch", csv_path, "-o", out, "--workers", "1")
    assert code == 1 and stdout.startswith("0 rendered, 1 skipped, 1 failed in ") and " on 1 worker; " in stdout
    code, stdout, stderr = cli("batch", inputs / "nothing.json", "-o", out)
    assert code == 1 and stderr == f"mpeg4fa batch: error: {inputs / 'nothing.json'}: no such manifest " \
                                   "(give a .json or .csv manifest)\n"
    with pytest.raises(SystemExit) as caught:
        cli("batch", csv_path, "-o", out, "--workers", "0")
    assert caught.value.code == 2
