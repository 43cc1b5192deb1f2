"""Run pyttsx3 once in its own process: ``python -m mpeg4fa.speech.tts._pyttsx3_worker``.

Reads ``{"text", "voice", "rate", "wav"}`` as JSON on stdin, writes the speech to ``wav`` and
prints ``{"words": [[position, length, sample], ...], "rate": hz}`` (or ``{"error", "hint"}``)
as the last line of stdout.

A process of its own because pyttsx3 drives the one espeak-ng instance a process may
initialise, which :mod:`.espeak` also uses. pyttsx3's espeak driver receives every word
event with its sample position but passes on only the text position; the hook below reads
the sample from the same event, which is the word boundary a SAPI 5 client gets in real time.
"""
from __future__ import annotations

import contextlib
import ctypes
import json
import os
import sys
import threading
import wave


def _load_pyttsx3():
    import espeakng_loader

    # pyttsx3 finds libespeak-ng by its soname: load the wheel's copy first, globally
    os.environ["ESPEAK_DATA_PATH"] = str(espeakng_loader.get_data_path())
    ctypes.CDLL(str(espeakng_loader.get_library_path()), mode=ctypes.RTLD_GLOBAL)
    import pyttsx3
    from pyttsx3.drivers import _espeak
    return pyttsx3, _espeak


def _voice_matches(espeak, voice: str) -> bool:
    current = espeak.GetCurrentVoice()
    if not current:
        return False
    v = current.contents
    names = [(x or b"").decode("utf-8", "replace").lower() for x in (v.name, v.identifier)]
    language = (v.languages or b"")[1:].decode("utf-8", "replace").lower()  # after the priority byte
    wanted = voice.lower()
    return wanted in names or wanted == language or names[1].endswith("/" + wanted)


def _set_voice(espeak, voice: str) -> bool:
    if espeak.SetVoiceByName(voice.encode("utf-8")) == 0 and _voice_matches(espeak, voice):
        return True
    spec = espeak.VOICE()
    spec.languages = voice.encode("utf-8")
    return espeak.SetVoiceByProperties(ctypes.byref(spec)) == 0 and _voice_matches(espeak, voice)


def run(request: dict) -> dict:
    with contextlib.redirect_stdout(sys.stderr):  # pyttsx3 prints "Audio saved to ..."
        pyttsx3, espeak = _load_pyttsx3()
        engine = pyttsx3.init("espeak")
        driver = engine.proxy._driver
        if not _set_voice(espeak, request["voice"]):
            return {"error": f"pyttsx3 has no voice {request['voice']!r}",
                    "hint": "use a voice name or language code espeak-ng knows, e.g. en-us, en-gb, cmn-latn-pinyin"}
        engine.setProperty("rate", int(request["rate"]))
        words: list[list[int]] = []
        audio: list[bytes] = []
        finished = threading.Event()
        forward = driver._onSynth

        def hook(wav, numsamples, events):
            if numsamples > 0:  # our own copy of every chunk espeak hands over (see below)
                audio.append(ctypes.string_at(wav, numsamples * ctypes.sizeof(ctypes.c_short)))
            i = 0
            while events[i].type != espeak.EVENT_LIST_TERMINATED:
                e = events[i]
                if e.type == espeak.EVENT_WORD:
                    words.append([e.text_position - 1, e.length, e.sample])
                elif e.type == espeak.EVENT_MSG_TERMINATED:
                    break
                i += 1
            status = forward(wav, numsamples, events)
            if events[i].type == espeak.EVENT_MSG_TERMINATED:
                finished.set()  # pyttsx3 has written the file
            return status

        espeak.SetSynthCallback(hook)
        engine.save_to_file(request["text"], request["wav"])
        engine.runAndWait()
        # runAndWait returns once espeak_Synth does, and in retrieval mode espeak may still be
        # speaking a long text on its own thread: wait for the end of the message
        espeak.Synchronize()
        if not finished.wait(request.get("timeout", 120.0)):
            return {"error": "pyttsx3 did not finish the speech in time", "hint": "split the text"}
        # the audio as espeak handed it over, written by us: pyttsx3's own buffer has come back short
        # now and then on a busy machine (a test caught 93,428 of 109,473 samples), ours never has
        with wave.open(request["wav"], "wb") as f:
            f.setnchannels(1)
            f.setsampwidth(2)
            f.setframerate(22050)
            f.writeframes(b"".join(audio))
    return {"words": words, "rate": 22050}


def main() -> int:
    try:
        result = run(json.loads(sys.stdin.read()))
    except Exception as exc:  # reported to the parent, which raises TTSError
        result = {"error": f"pyttsx3 failed: {exc!r}", "hint": "check that pyttsx3==2.99 and espeakng-loader are installed"}
    print(json.dumps(result))
    return 1 if "error" in result else 0


if __name__ == "__main__":
    sys.exit(main())
