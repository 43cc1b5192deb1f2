"""Lip sync from a recording alone (issue 28): how close the audio-only viseme track comes to the transcript
path's, how still the mouth stays through noise and music, and how fast it runs.

Speech: espeak-ng sentences (each spoken by a fresh process, tools/espeak_fresh.py: the same audio every run) in
English, Spanish, French, German, Mandarin and Hindi, whose phone times are known (espeak-ng's own events): the
``old`` set (:data:`SPEECH`: 5 English, 3 a language) and ``all``, which adds :data:`MORE` (12 English sentences
in two voices, 6 a language in two or three voices; 45-230 closures a language in all). The transcript path's
track is the utterance the text path makes of the same text (:func:`mpeg4fa.speech.utterance.speak`, stops
moved to their closures): the track a perfect aligner would give. Mandarin is spoken through espeak-ng's ``cmn``
voice on the IPA route, so that both tracks use the 14 MPEG-4 visemes (the pinyin route's Chinese visemes have
no PP to compare). The audio-only track is :func:`mpeg4fa.speech.listen.listen` of the audio alone, recogniser
``phonetic`` (all), ``words`` and ``either`` (English); the phonetic one's p, b and m placed by the closure
detector (:mod:`mpeg4fa.speech.listen.closures`), which tools/train_listen_closures.py trains on espeak-ng
pseudo-words, never these sentences.

Measured (:mod:`mpeg4fa.speech.listen.compare`): closure onsets (viseme PP: p, b, m) found within 40 ms; the
reference's closures are those that shut the lips (:func:`~mpeg4fa.speech.listen.compare.shuts`): espeak-ng
speaks Spanish b/v between vowels (and after s, l, r) as [β], the lips near but never shut and no stop's
silence in the sound; the text path shows it as PP, but no recording has a closure onset there to find (15 of
the enlarged set's 58 Spanish closures, counted until 2026-12-05; a closure shown there is not extra either); the
mean error of those found within 100 ms; beside it (``within_40ms_from_rest``), closures the reference begins
from rest counted found where the audio-only track shows the lips shut or at rest at that onset
(:func:`~mpeg4fa.speech.listen.compare.onset_score` ``from_rest``; the neutral face's lips are in contact, so
the reference's onset there is no movement: a b or p that starts the file, after silence; Mandarin's p, whose
closure espeak-ng books as a pause event of digital silence before the stop, which the transcript path leaves
at rest, 2026-12-05); the closures the audio-only track shows (found) and those of them
farther than 100 ms from any in the transcript's track (extra; precision = 1 - extra / found); per-frame viseme
agreement at 25 fps (frames where both rest left out). Rest: silence, white noise at -30 dBFS and synthetic
music (:mod:`mpeg4fa.speech.listen.signals`), the share of 25 fps frames with no viseme shown and the share with
the jaw and lips (FAPs 3-17) within one unit of neutral. Speed: :func:`~mpeg4fa.speech.listen.stream.stream_listened`
of 60 s of English (espeak-ng's, and with ``--human`` the recordings of people) to an FBA stream, seconds of
audio per wall second with two blocks heard at once (the load average is printed: the machine is shared) and per
second of CPU time with one process doing all (pocketsphinx runs on one thread: what an idle core gives).

``--human DIR``: also recordings of people, each ``NAME.wav`` with its transcript ``NAME.txt`` (e.g. the
LibriVox files of pocketsphinx's source package, test/data/librivox, as tools/bench_align.py --human uses):
the transcript path is then :func:`~mpeg4fa.speech.align.align_recording` of the transcript.

    .venv/bin/python tools/bench_lipsync_audio.py [--json tools/bench_lipsync_audio.json] [--human DIR] [--quick]
        [--without-detector] [--speed-only] [--lengths 5,10,25,60,600] [--repeat 3] [--hour 60]
"""
from __future__ import annotations

import argparse
import io
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from espeak_fresh import spoken  # noqa: E402

from mpeg4fa.speech.align import Recording, align_recording, read_recording  # noqa: E402
from mpeg4fa.speech.encoder import encode_utterance, phones  # noqa: E402
from mpeg4fa.speech.listen import listen  # noqa: E402
from mpeg4fa.speech.listen.compare import agreement, closure_onsets, onset_score, rest_share  # noqa: E402
from mpeg4fa.speech.listen.signals import music, white_noise  # noqa: E402
from mpeg4fa.speech.listen.stream import Source, stream_listened  # noqa: E402

SPEECH = {
    "en": [("en-us", "Please bring the maps back before the boat leaves."),
           ("en-us", "Peter picked a peck of pickled peppers, and my mother baked bread."),
           ("en-us+f3", "My brother bought a big blue umbrella from the market."),
           ("en-gb", "Bob might move the piano before the bus comes by."),
           ("en-us+m3", "Maybe the puppy wants more bread and some apple pie.")],
    "es": [("es", "Mi madre compró pan y manzanas en el mercado."),
           ("es", "Pablo bebe un poco de vino blanco por la mañana."),
           ("es", "El bombero abrió la puerta de la biblioteca.")],
    "fr": [("fr", "Mon petit frère mange une pomme sur le banc."),
           ("fr", "Paul a bu beaucoup de bière belge au bistrot."),
           ("fr", "Ma mère prépare un bon repas pour papa.")],
    "de": [("de", "Meine Mutter backt Brot am Montagmorgen."),
           ("de", "Peter bringt die Butter und das Brot mit."),
           ("de", "Im Sommer baden wir im blauen Meer.")],
    "zh": [("cmn", "妈妈买了面包和苹果。"), ("cmn", "爸爸不喜欢喝咖啡，他每天喝茶。"), ("cmn", "朋友们明天去北京爬山。")],
    "hi": [("hi", "मेरा भाई बाजार से पानी लाया।"), ("hi", "बाबा ने मुझे एक बड़ा पत्थर दिया।"),
           ("hi", "माँ ने मुझे मीठा पराठा बनाकर दिया।")],
}
MORE = {
    "en": [(v, t) for t in ("The baby played with a purple ball in the back garden.",
                            "Mark put the empty box beside the map on my desk.",
                            "Before lunch, Pam bought some plums and a jar of maple syrup.",
                            "Please remember to bring your passport to the embassy by Monday.",
                            "The membership committee approved the budget in September.",
                            "My aunt keeps bees, ponies and a small black lamb on her farm.",
                            "Bill imagined a ship moving slowly past the bright lamps of the bay.",
                            "The plumber promised to come back tomorrow morning at nine.",
                            "A bumblebee buzzed above the pink blossoms by the pond.",
                            "Ben's grandmother baked a pumpkin pie for the party.",
                            "Jump up and grab the rope, then pull yourself to the top.",
                            "Maybe Emma will bring popcorn to the movie premiere.")
           for v in ("en-us", "en-gb-x-rp+f3")],
    "es": [("es", "Pedro compró un paraguas morado en Barcelona."),
           ("es+f3", "Mañana por la mañana bebemos café con leche y pan."),
           ("es", "El pequeño perro sube por la rampa del jardín."),
           ("es+m2", "Mi primo Miguel trabaja en un barco de pesca."),
           ("es", "Para el examen, Beatriz estudió mucho el mapa de Perú."),
           ("es+f3", "Las palomas buscan migas bajo el puente.")],
    "fr": [("fr", "Le boulanger prépare des baguettes pour le marché du matin."),
           ("fr+f2", "Pierre aime beaucoup la musique de Bach et de Brahms."),
           ("fr", "Mon ami Benoît habite près du pont de la mer."),
           ("fr+m3", "Nous mangeons des pommes et du pain sous le parapluie."),
           ("fr", "Maman met un beau bouquet de marguerites sur la table."),
           ("fr+f2", "Le pompier monte par l'échelle jusqu'au balcon.")],
    "de": [("de", "Mein Bruder bäckt am Mittwoch einen Pflaumenkuchen."),
           ("de+f3", "Der Bäcker bringt morgens frische Brötchen mit Butter."),
           ("de", "Paula malt ein blaues Boot am Meer."),
           ("de+m1", "Im Park spielen Mädchen und Buben mit dem Ball."),
           ("de", "Bitte nimm das Paket mit zur Post am Bahnhof."),
           ("de+f3", "Mama kauft Milch, Mehl und Pilze auf dem Markt.")],
    "zh": [("cmn", "我们明天早上吃面包和牛奶。"), ("cmn+f3", "妹妹把苹果放在盘子里。"),
           ("cmn", "爸爸妈妈每年冬天去北边旅游。"), ("cmn+f3", "门口有一辆白色的面包车。"),
           ("cmn", "老板买了八本漂亮的笔记本。"), ("cmn+f3", "你明白我们的意思吗？")],
    "hi": [("hi", "बाबूजी ने बाजार से बैंगन और पपीता खरीदा।"), ("hi+f2", "मैं सुबह पार्क में भागता हूँ।"),
           ("hi", "पापा ने मुझे एक बड़ी किताब भेजी।"), ("hi+f2", "बच्चे बगीचे में फूल और पत्ते देख रहे हैं।"),
           ("hi", "मेरी बहन मुंबई में पढ़ाई करती है।"), ("hi+f2", "बादल बरसे और पानी भर गया।")],
}
"""The enlarged set (written for this benchmark, natural text with many p, b, m; other voices): scored with
:data:`SPEECH` as ``set`` ``all``, beside ``old`` (:data:`SPEECH` alone, the figures before it)."""
ENGLISH = ("phonetic", "words", "either")
"""The recognisers measured on English (:data:`mpeg4fa.speech.listen.RECOGNIZERS` less ``auto``, which is one
of them); the other languages: ``phonetic``."""
TARGET = {"en": 0.90}
OTHER_TARGET = 0.75
RATE = 160


def _score(ref_timings, heard_timings, duration: float) -> dict:
    s = onset_score(ref_timings, heard_timings)
    a, n = agreement(ref_timings, heard_timings, duration)
    return {"closures": s.reference, "hits": s.hits,
            "hits_from_rest": onset_score(ref_timings, heard_timings, from_rest=True).hits,
            "errors": list(s.errors), "extra": s.extra,
            "found": len(closure_onsets(heard_timings)), "agree_frames": a * n if n else 0.0, "frames": n}


def _sum(rows: list[dict]) -> dict:
    closures = sum(r["closures"] for r in rows)
    hits = sum(r["hits"] for r in rows)
    errors = [e for r in rows for e in r["errors"]]
    frames = sum(r["frames"] for r in rows)
    found, extra = sum(r["found"] for r in rows), sum(r["extra"] for r in rows)
    rest = sum(r["hits_from_rest"] for r in rows)
    return {"closures": closures, "within_40ms": hits / closures if closures else float("nan"),
            "within_40ms_from_rest": rest / closures if closures else float("nan"),
            "mean_onset_error_ms": 1000 * float(np.mean(errors)) if errors else float("nan"),
            "found": found, "extra_closures": extra, "precision": (found - extra) / found if found else float("nan"),
            "frame_agreement": sum(r["agree_frames"] for r in rows) / frames if frames else float("nan"),
            "frames": frames}


def run_speech(quick: bool) -> list[dict]:
    """Rows per language and recogniser for the ``old`` set (:data:`SPEECH`) and ``all`` (with :data:`MORE`)."""
    rows = []
    for lang in SPEECH:
        per = {(which, how): [] for which in ("old", "new") for how in ENGLISH}
        for which, items in (("old", SPEECH[lang]), ("new", MORE[lang])):
            for voice, text in items[:2] if quick else items:
                code = voice.split("+")[0] if lang != "en" else "en"
                ref = phones(spoken(text, lang=code, voice=voice, rate=RATE))
                rec = Recording(ref.speech.samples, ref.speech.rate, text)
                for how in (ENGLISH if lang == "en" else ("phonetic",)):
                    heard = listen(rec, recognizer=how, lang=code)
                    per[which, how].append(_score(ref.timings, phones(heard.utterance).timings, rec.duration))
        for how in ENGLISH:
            for which, got in (("old", per["old", how]), ("all", per["old", how] + per["new", how])):
                if got:
                    rows.append({"lang": lang, "set": which, "recognizer": how, "sentences": len(got), **_sum(got)})
    return rows


def run_human(folder: Path) -> list[dict]:
    per: dict[str, list[dict]] = {how: [] for how in ENGLISH}
    for wav in sorted(folder.glob("*.wav")):
        txt = wav.with_suffix(".txt")
        if not txt.exists():
            continue
        rec = read_recording(wav)
        ref = phones(align_recording(rec, txt.read_text(encoding="utf-8").strip(), lang="en").utterance)
        for how in per:
            heard = listen(rec, recognizer=how, lang="en")
            per[how].append(_score(ref.timings, phones(heard.utterance).timings, rec.duration))
    return [{"lang": "en (human)", "set": "human", "recognizer": how, "sentences": len(got), **_sum(got)} for how, got in per.items()
            if got]


def _int16(x: np.ndarray) -> np.ndarray:
    return np.clip(np.rint(x * 32768), -32768, 32767).astype(np.int16)


def run_rest(seconds: float) -> list[dict]:
    rate = 16000
    clips = [("silence", np.zeros(int(seconds * rate))),
             ("white noise -30 dBFS", white_noise(seconds, rate, -30.0)),
             ("music -18 dBFS", music(seconds, rate, -18.0, seed=0)),
             ("music -12 dBFS (seed 3)", music(seconds, rate, -12.0, seed=3))]
    rows = []
    for name, x in clips:
        rec = Recording(_int16(x), rate, name)
        heard = listen(rec, recognizer="phonetic")
        enc = encode_utterance(heard.utterance, level="low")
        mouth = np.abs(enc.values[:, 2:17]).max(axis=1)
        rows.append({"clip": name, "seconds": seconds, "rest_frames": rest_share(heard.utterance.timings, rec.duration),
                     "mouth_neutral_frames": float((mouth <= 1).mean())})
    return rows


def espeak_clip(seconds: float) -> tuple[np.ndarray, int]:
    """At least ``seconds`` of the English sentences of :data:`SPEECH` in en-us, one after another."""
    said = [spoken(t, lang="en", voice="en-us", rate=RATE).speech for _, t in SPEECH["en"]]
    parts, total = [], 0.0
    while total < seconds:
        s = said[len(parts) % len(said)]
        parts.append(s.samples)
        total += s.duration
    return np.concatenate(parts), s.rate


def human_clip(folder: Path, seconds: float) -> tuple[np.ndarray, int]:
    """At least ``seconds`` of the recordings ``NAME.wav`` in ``folder`` (one rate), one after another."""
    recs = [read_recording(w) for w in sorted(folder.glob("*.wav"))]
    parts, total = [], 0.0
    while total < seconds:
        r = recs[len(parts) % len(recs)]
        parts.append(r.samples)
        total += r.duration
    return np.concatenate(parts), recs[0].rate


def _forked(x: np.ndarray, rate: int, how: str, two_cores: bool) -> bytes:
    """The stream and timings :func:`stream_listened` writes for ``x``, heard in a process forked from this one:
    pocketsphinx's decoders carry state (their cepstral means) from one utterance to the next, so two runs in one
    process differ a little; forked, each starts from the same state."""
    import pickle

    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: hear, send, leave without the parent's exit handlers
        os.close(read)
        try:
            out, timings = io.BytesIO(), io.StringIO()
            stream_listened(Source("same", rate, len(x) / rate, iter([x])), out, timings=timings, recognizer=how,
                            lang="en", two_cores=two_cores)
            data = pickle.dumps((out.getvalue(), timings.getvalue()))
        except BaseException as exc:  # noqa: BLE001 - reported by the parent
            data = pickle.dumps(repr(exc))
        with os.fdopen(write, "wb") as fh:
            fh.write(data)
        os._exit(0)
    os.close(write)
    with os.fdopen(read, "rb") as fh:
        data = fh.read()
    os.waitpid(pid, 0)
    got = pickle.loads(data)
    if isinstance(got, str):
        raise SystemExit(f"the forked run failed: {got}")
    return got[0] + got[1].encode()


def _children_cpu() -> float:
    """CPU seconds of this process's ended children (the helper process of :func:`stream_listened`)."""
    import resource

    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_speed(clips: dict[str, tuple[np.ndarray, int]], lengths: tuple[float, ...] = (60.0,), repeat: int = 1,
              recognizers: tuple[str, ...] = ENGLISH) -> list[dict]:
    """Each clip, cut to each of ``lengths`` seconds, through :func:`stream_listened` by each recogniser: wall
    time with both cores (``two_cores``, the default: two blocks at once, or a lone block's phone loop beside its
    word decoding under ``either``; the load average printed: the machine is shared), the best of ``repeat``
    runs, and CPU time with one process doing all (``two_cores`` off: the process's CPU time is then all the work,
    what one idle core gives). ``x_real_time_idle``: the audio's seconds over the larger CPU time of the two processes
    of the best run (this one, ``cpu_here_s``, and its helper, ``cpu_helper_s``): the speed two idle cores would give,
    the two working at once, whatever else loads a shared machine. ``same`` (clips up to 2 min): the two give the
    same stream and timings, byte for byte (:func:`_forked`): expected of the phones path at any length (each
    utterance is decoded from a fresh decoder's state, :func:`~mpeg4fa.speech.listen.phones.decode_pcm`), and of
    the words path for one block only (a clip of 4 s or more is two: :func:`~mpeg4fa.speech.listen.stream.blocks`):
    its alignment is the transcript aligner's, whose decoder carries its front end's state from one alignment to
    the next and which hears espeak-ng's rendering of the words, whose audio depends on what the process spoke
    before."""
    rows = []
    for clip, (whole, rate) in clips.items():
        stream_listened(Source("warm", rate, 3.0, iter([whole[:3 * rate]])), io.BytesIO(), lang="en",
                        two_cores=False)  # the models loaded and the encoder compiled before the clock starts
        for length in lengths:
            x = whole[:int(length * rate)]
            seconds = len(x) / rate
            for how in recognizers:
                walls, loads, cpus = [], [], []
                for _ in range(repeat):
                    loads.append(os.getloadavg()[0])
                    here, helper = time.process_time(), _children_cpu()
                    started = time.perf_counter()
                    heard = stream_listened(Source("speed", rate, seconds, iter([x])), io.BytesIO(), recognizer=how,
                                            lang="en")
                    walls.append(time.perf_counter() - started)
                    cpus.append((time.process_time() - here, _children_cpu() - helper))
                cpu = time.process_time()
                stream_listened(Source("speed", rate, seconds, iter([x])), io.BytesIO(), recognizer=how, lang="en",
                                two_cores=False)
                cpu = time.process_time() - cpu
                same = (_forked(x, rate, how, True) == _forked(x, rate, how, False)) if seconds <= 120 else None
                wall = min(walls)
                here, helper = cpus[walls.index(wall)]
                rows.append({"clip": clip, "recognizer": how, "used": heard.recognizer, "seconds": seconds,
                             "wall_s": wall, "x_real_time": seconds / wall, "walls_s": walls, "cpu_s": cpu,
                             "x_real_time_cpu": seconds / cpu, "cpu_here_s": here, "cpu_helper_s": helper,
                             "x_real_time_idle": seconds / max(here, helper, 1e-9), "cpus": os.cpu_count(),
                             "load_average": loads[walls.index(wall)], "frames": heard.frames,
                             "same": same})
    return rows


def print_speed(speed: list[dict]) -> None:
    print(f"\n{'clip':<10} {'recogniser':<10} {'used':<9} {'audio s':>8} {'wall s':>7} {'x real time':>11} "
          f"{'CPU s':>6} {'x per CPU s':>11} {'x idle':>6} {'cpus':>5} {'load':>5} {'same':>5}   (target >= 10x on 2 "
          f"cores; 'x per CPU s': one process doing all, what one idle core gives; 'x idle': over the busier process's "
          f"CPU time, what two idle cores give)")
    for r in speed:
        print(f"{r['clip']:<10} {r['recognizer']:<10} {r['used']:<9} {r['seconds']:>8.1f} {r['wall_s']:>7.2f} "
              f"{r['x_real_time']:>11.1f} {r['cpu_s']:>6.2f} {r['x_real_time_cpu']:>11.1f} "
              f"{r.get('x_real_time_idle', float('nan')):>6.1f} {r['cpus']:>5} "
              f"{r['load_average']:>5.1f} {str(r.get('same', '')):>5}")


_PEAK = ("import resource, subprocess, sys; rc = subprocess.run(sys.argv[1:]).returncode; "
         "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss); sys.exit(rc)")
"""Runs a command and prints the peak resident set (kB) of the largest of its processes: a process of its own,
so that the benchmark's own children (its forks, its helpers) are not counted."""


def run_hour(x: np.ndarray, rate: int, seconds: float, recognizer: str) -> dict:
    """``mpeg4fa encode --speech`` (a process of its own) of ``x`` repeated to ``seconds``, written as a WAV
    file: its speed and the peak memory (resident set) of the largest of its processes, a helper included
    (the memory of a block: it should not grow with the length)."""
    import subprocess
    import tempfile
    import wave

    with tempfile.TemporaryDirectory() as tmp:
        wav = Path(tmp) / "long.wav"
        with wave.open(str(wav), "wb") as w:
            w.setnchannels(1)
            w.setsampwidth(2)
            w.setframerate(rate)
            left = int(seconds * rate)
            while left > 0:
                w.writeframes(x[:left].tobytes())
                left -= len(x[:left])
        load = os.getloadavg()[0]
        started = time.perf_counter()
        cli = str(Path(sys.executable).parent / "mpeg4fa")
        done = subprocess.run([sys.executable, "-c", _PEAK, cli, "encode", "--speech", str(wav), "--recognizer",
                               recognizer, "--lang", "en", "-o", str(Path(tmp) / "long.fba")],
                              capture_output=True, text=True)
        wall = time.perf_counter() - started
        if done.returncode:
            raise SystemExit(done.stderr)
        peak = int(done.stdout.split()[-1]) / 1024
        said = [line for line in done.stderr.splitlines() if "recognised" in line or "heard" in line]
    return {"seconds": seconds, "recognizer": recognizer, "wall_s": wall, "x_real_time": seconds / wall,
            "peak_mb": peak, "load_average": load, "said": said}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--json", type=Path, help="write the figures here")
    ap.add_argument("--human", type=Path, metavar="DIR", help="also NAME.wav + NAME.txt recordings of people")
    ap.add_argument("--quick", action="store_true", help="two sentences a language from each set, 10 s clips, 20 s "
                                                           "speed test")
    ap.add_argument("--without-detector", action="store_true",
                    help="the phone loop's own p, b, m (the closure detector off): the figures before it")
    ap.add_argument("--speed-only", action="store_true",
                    help="only the speed (with --json: its rows replace the file's rows of the same clip, "
                         "recogniser and length, the rest kept)")
    ap.add_argument("--lengths", default=None, help="seconds of each speed clip, comma separated (default 60; "
                                                      "--quick 20)")
    ap.add_argument("--repeat", type=int, default=1, help="speed: the best wall time of this many runs")
    ap.add_argument("--hour", type=float, metavar="MIN", help="also MIN minutes of the clip(s) through "
                                                                 "'mpeg4fa encode --speech' (auto): speed, peak memory")
    args = ap.parse_args()
    lengths = tuple(float(v) for v in args.lengths.split(",")) if args.lengths else ((20.0,) if args.quick else (60.0,))
    if args.speed_only:
        clips = {"espeak-ng": espeak_clip(max(lengths))}
        if args.human is not None:
            clips["human"] = human_clip(args.human, max(lengths))
        speed = run_speed(clips, lengths, args.repeat, ("either",) if len(lengths) > 1 else ENGLISH)
        print_speed(speed)
        hour = [run_hour(*clips[c], args.hour * 60, "auto") | {"clip": c} for c in clips] if args.hour else []
        for r in hour:
            print(f"{r['clip']}: {r['seconds'] / 60:.0f} min through encode --speech: "
                  f"{r['x_real_time']:.1f}x real time (load {r['load_average']:.1f}), peak memory "
                  f"{r['peak_mb']:.0f} MB; {' / '.join(r['said'])}")
        if args.json is not None:
            figures = json.loads(args.json.read_text(encoding="utf-8")) if args.json.exists() else {}
            new = {(r["clip"], r["recognizer"], round(r["seconds"])) for r in speed}
            figures["speed"] = [r for r in figures.get("speed", [])
                                if (r["clip"], r["recognizer"], round(r["seconds"])) not in new] + speed
            if hour:
                figures["hour"] = hour
            args.json.write_text(json.dumps(figures, indent=1) + "\n", encoding="utf-8")
            print(f"wrote {args.json}")
        return
    if args.without_detector:
        from functools import partial

        from mpeg4fa.speech.listen import core
        from mpeg4fa.speech.listen.phones import recognize_phones

        core.recognize_phones = partial(recognize_phones, closures=False)
    speech = run_speech(args.quick)
    if args.human is not None:
        speech += run_human(args.human)
    print(f"{'lang':<11} {'set':<5} {'recogniser':<9} {'sent':>4} {'PP':>4} {'<=40ms':>7} {'+rest':>6} {'target':>6} {'err ms':>6} "
          f"{'found':>5} {'extra':>5} {'prec':>5} {'agree':>6}")
    for r in speech:
        target = TARGET.get(r["lang"].split()[0], OTHER_TARGET)
        print(f"{r['lang']:<11} {r['set']:<5} {r['recognizer']:<9} {r['sentences']:>4} {r['closures']:>4} "
              f"{r['within_40ms']:>7.1%} {r['within_40ms_from_rest']:>6.1%} {target:>6.0%} "
              f"{r['mean_onset_error_ms']:>6.1f} {r['found']:>5} {r['extra_closures']:>5} "
              f"{r['precision']:>5.1%} {r['frame_agreement']:>6.0%}")
    en = [r for r in speech if r["lang"].startswith("en") and r["set"] in ("all", "human")]
    pooled = {how: sum(r["within_40ms"] * r["closures"] for r in en if r["recognizer"] == how)
              / sum(r["closures"] for r in en if r["recognizer"] == how) for how in ENGLISH}
    better = max(pooled, key=pooled.get)
    print(f"English: {better} matches the transcript path best (closures within 40 ms, espeak-ng's speech"
          f"{' and the recordings of people' if args.human else ''} pooled: "
          + ", ".join(f"{k} {v:.1%}" for k, v in pooled.items()) + ")")
    rest = run_rest(10.0 if args.quick else 30.0)
    print(f"\n{'clip':<26} {'rest frames':>11} {'mouth neutral':>13}   (target >= 95 %)")
    for r in rest:
        print(f"{r['clip']:<26} {r['rest_frames']:>11.1%} {r['mouth_neutral_frames']:>13.1%}")
    clips = {"espeak-ng": espeak_clip(max(lengths))}
    if args.human is not None:
        clips["human"] = human_clip(args.human, max(lengths))
    speed = run_speed(clips, lengths, args.repeat)
    print_speed(speed)
    if args.json is not None:
        args.json.write_text(json.dumps({"speech": speech, "english_better": better, "rest": rest, "speed": speed},
                                        indent=1) + "\n", encoding="utf-8")
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
