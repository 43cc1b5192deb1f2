"""Live lip sync: audio chunks in, FAP frames out, a fixed latency behind the audio.

Why a module of its own: the offline paths know the whole recording (or the text) before the first
frame; a microphone gives 20 ms at a time and the face must follow it while it speaks. This one
listens with pocketsphinx's phone loop (``allphone``, the model :func:`~.align.sphinx.free_decoder`
uses, bundled in the wheel), maps the phones to the MPEG-4 visemes as a recording without a transcript
has them (:mod:`.listen.phones`: IPA, then the text path's feature map), and moves the mouth by
the timeline's own rules (:mod:`.timeline`'s moves, :mod:`.frames`' merging and rounding), so a
live face moves as an encoded one does.

How (the numbers are the defaults; ``tools/bench_live.py`` measures them):

- Windows: every :data:`HOP` s (80 ms) a window of the last :data:`WINDOW` s (320 ms) of audio ends,
  decoded as one utterance (the phone loop gives no timed phones before an utterance ends). Four
  decoders, staggered by a hop, each hear every sample as it comes (``process_raw`` per chunk), so
  the work is spread evenly over the chunks (no chunk pays for a whole window). The phones a window
  finds up to :data:`SETTLE` s before its end (0: to its end) are *committed*: from the previous commit to
  there, the face's phones are that window's, and never change again; the 240 ms before its newest
  hop give them their left context.
- A committed phone becomes a viseme span, or two (a diphthong, an affricate), by the recording path's map
  (:func:`phone_parts`); silence and fillers are a gap, the mouth at rest. The move into
  a span is made when the span starts, its lag as for a phone of full length; the span grows as it is
  heard; when silence follows, the move back to rest is made at once, as into a long silence.
- A move into a shape starts up to :data:`~.timeline.LEAD` (100 ms) before the phone, so a frame is
  final once the commits reach ``LEAD`` past it. Frame ``k`` (time ``k / fps``) is emitted when the
  audio fed reaches ``k / fps + latency``: exactly, whatever the chunk size, with
  ``latency = HOP + SETTLE + LEAD`` (180 ms) by default. The first movement of the mouth therefore
  shows about ``latency - LEAD`` after the speech starts (the anticipation hides the rest).
- Voice: a 10 ms frame is voiced when pocketsphinx's voice activity detector (:class:`pocketsphinx.Vad`)
  hears speech in it and its spectrum is not flat (:func:`flatness`, white noise). A phone over
  unvoiced frames (more than :data:`REACH` after voice) is silence whatever the loop calls it, so
  silence and noise keep the mouth at rest; voice the loop still calls silence (the first window or two of speech) takes :data:`VOICE_VISEME`.
  Music is voice to the detector; it is told from a voice by its pitch (:meth:`LiveLipSync._notes`, the
  recording path's tests on the frames already heard): a pitch held for :data:`STEADY` s is a note, and so
  is a second in which at least :data:`MUSIC_SHARE` of the periodic frames keep their pitch (several notes
  at once, plucked and decaying); everything for :data:`MUSIC_HOLD` s after either is music too. Each
  frame's pitch is taken on the 32 ms that end with it, its period the shortest lag near the best (a
  pure tone's autocorrelation is as high at each multiple of its period). Measured (8 s each, 2026-12-05;
  tests/speech/test_live.py holds the melodies, the music and the speech to them; tools/bench_live.py's
  rest rows measure silence, -30 dBFS noise and the music: 100 %, 100 %, 96.5 %): a held chord, melodies
  of pure, sawtooth and organ tones (220-880 Hz,
  0.3 s notes, -12 dBFS) and the synthetic music of :mod:`.listen.signals` leave the mouth at rest in
  96.5-100 % of their frames (before: 98 % for the chord, 18-65 % for the melodies, 8 % for the music: the
  pitch was taken on windows running past the audio heard, and jumped between a tone's subharmonics);
  espeak-ng speech in en, es, de, fr moves the mouth in 98.9-100 % of its frames, as before.

Frames are ``(n, 68)`` low-level FAPs, rounded (column ``i`` is FAP ``i + 1``), as
:class:`~.frames.FrameBlock` carries them: :meth:`LiveLipSync.feed` returns those that became due
(possibly none), :meth:`LiveLipSync.flush` the rest, to the end of the audio fed. :class:`LiveEncoder`
codes each batch as a complete fba_object (the text path's stream pass, :class:`~.encoder.StreamBuilder`),
as ``mpeg4fa serve`` sends them to its page (:mod:`mpeg4fa.serve.microphone`).
"""
from __future__ import annotations

import math
from functools import lru_cache
from pathlib import Path

import numpy as np

from mpeg4fa.spec import N_FAPS
from mpeg4fa.speech.align.sphinx import OFFSET, RATE
from mpeg4fa.speech.frames import FrameMaker
from mpeg4fa.speech.timeline import LAG, LAG_SHARE, LEAD, VisemeSpan, _checked_spans

HOP = 0.08
"""Seconds of audio between two decodings."""
WINDOW = 0.32
"""Seconds of audio each decoding reads (its newest :data:`HOP` and the context before)."""
SETTLE = 0.0
"""The newest part of a window (s) whose phones are not committed. Measured (90 s of espeak-ng speech,
tools/bench_live.py's quality rows): committing to the window's very end agrees with the text path's
visemes as often as keeping its last 20 ms back (28.6 % and 29.1 % of frames) and shows the mouth
30 ms sooner; so nothing is kept back.
"""
LATENCY = HOP + SETTLE + LEAD
"""The default latency (s): frame ``k`` comes out when the audio fed reaches ``k / fps`` plus this."""
VAD_MODE = 3
"""pocketsphinx's voice activity detector's aggressiveness (0-3); 3 hears least noise as voice."""
VAD_FRAME = 0.01
"""The detector's frame (s)."""
VERDICTS_KEPT = int(round(2 * WINDOW / VAD_FRAME))
"""The detector's newest verdicts kept (two windows' worth)."""
FLAT = 0.3
"""Spectral flatness (0..1) from which a 10 ms frame is noise, not a voice: white noise has about 0.56
(a periodogram's geometric over arithmetic mean, e^-0.577), voiced speech below 0.1."""
VOICE_VISEME = "E"
"""The shape of a voice the phone loop has not made out yet (it calls the start of speech silence for a
window or two): the neutral vowel's, as espeak-ng's schwa ``@`` has it."""
STEADY = 0.15
"""A pitch held this long (s) is a note of music, not a voice (:data:`~.listen.voice.STEADY_SECONDS`)."""
MUSIC_HOLD = 0.5
"""Seconds after a held note that are music too (the next note's onset comes before its steadiness)."""
HELD_CENTS = 10.0
"""A pitch that moves less than this (cents) is held. Tighter than the recording path's
:data:`~.listen.voice.STEADY_CENTS` (15): the pitch here lies between whole lags, where a note holds within
1-4 cents and a voice's glides show; at 15 cents a sentence-final "ah" of espeak-ng held the mouth shut."""
MUSIC_SUNG = 0.2
"""Seconds of periodic sound within the last second before the share rule may call it music (a voice's
first syllable can hold its pitch for a few frames)."""
MUSIC_SHARE = 0.33
"""Share of the periodic frames of the last second whose pitch holds (within :data:`HELD_CENTS` of the pitch
:data:`~.listen.voice.STEADY_SECONDS` before) from which it is music. Measured with this module's pitch
(2026-12-05): espeak-ng speech in en, es, de, fr at most 0.14-0.19 (median 0.04-0.08); the synthetic music
of :mod:`.listen.signals` at least 0.36 (median 0.55-0.64), melodies of pure, sawtooth and organ tones at
least 0.65."""
VOICE_RATE = 8000
"""The rate the recording path measures pitch at (:data:`~.listen.voice.RATE`); its lags are scaled from it."""
PITCH_WINDOW = 512
"""16 kHz samples each frame's pitch is measured on (32 ms, the recording path's window)."""
CONTEXT = PITCH_WINDOW - int(round(0.01 * RATE))
"""16 kHz samples kept from before the new frames, so that the first one's window is whole."""
REACH = 0.15
"""Seconds after voice in which a phone the loop hears stays a phone though unvoiced (as the recording
path's :data:`~.listen.voice.REACH` widens speech, here on the side already heard only)."""
_HOP_10MS = 0.01
_SILENT = frozenset({"SIL", "+NSN+", "+SPN+", "+BREATH+", "+COUGH+", "+UM+", "+NOISE+", "+SMACK+", "+UH+"})


@lru_cache(maxsize=None)
def phone_parts(phone: str) -> tuple[tuple[str, float, float], ...]:
    """An ARPAbet phone's mouth shapes as (viseme, start, end) shares of its time, by the recording path's
    map (:func:`mpeg4fa.speech.listen.phones.phone_timings`: the phone's IPA, ``spec/arpabet_ipa.csv``,
    through the IPA feature map; a diphthong or an affricate in two parts); empty for silence, a filler
    or a phone the table lacks."""
    from mpeg4fa.speech.listen.phones import arpabet_ipa, phone_timings
    from mpeg4fa.speech.tts.base import Event
    from mpeg4fa.speech.visemes import PAUSE

    ipa = arpabet_ipa().get(phone)
    if phone in _SILENT or not ipa:
        return ()
    return tuple((t.viseme, t.start, t.end) for t in phone_timings([Event("phoneme", 0.0, 1.0, ipa)], where="live")
                 if t.viseme != PAUSE)


def _decoder():
    """A phone-loop decoder of its own (one per window: decoders are not shared across threads), tuned as the
    recording path's (:func:`mpeg4fa.speech.listen.phones.phone_decoder`: the phone trigram's weight
    lowered, so the acoustics are heard: p, b, m among them)."""
    from mpeg4fa.extras import require

    require("align", "pocketsphinx")
    from pocketsphinx import Decoder, get_model_path

    from mpeg4fa.speech.listen.phones import LANGUAGE_WEIGHT

    phone_lm = Path(get_model_path()) / "en-us" / "en-us-phone.lm.bin"
    return Decoder(samprate=RATE, allphone=str(phone_lm), bestpath=False, loglevel="FATAL", lw=LANGUAGE_WEIGHT)


class LiveLipSync:
    """Audio chunks in (mono PCM: int16 samples, or bytes of s16le), FAP frames out, ``latency`` s late.

    ``rate``: the audio's sample rate (anything; it is resampled to the model's 16 kHz as it comes,
    :class:`Resampler`);
    ``fps``: frames per second; ``idle``: blinks and head motion as the encoder's ``--idle`` gives them;
    ``latency``: at least :data:`LATENCY` (more only delays the frames, it buys nothing);
    ``keep_spans``: keep every viseme span (:attr:`timings`, for measuring; a long session's grow).
    """

    def __init__(self, rate: int = RATE, fps: float = 25.0, *, latency: float = LATENCY, idle: bool = False,
                 seed: int = 0, keep_spans: bool = False) -> None:
        if isinstance(rate, bool) or not isinstance(rate, (int, np.integer)) or not 4000 <= rate <= 192000:
            raise ValueError(f"rate {rate!r} must be an integer number of Hz in 4000..192000")
        if not (isinstance(latency, (int, float)) and math.isfinite(latency) and latency >= LATENCY - 1e-9):
            raise ValueError(f"latency {latency!r} must be at least {LATENCY:.2f} s (hop, settle and lead)")
        self.rate, self.latency = int(rate), float(latency)
        from mpeg4fa.speech.encoder import closure_hold

        self.maker = FrameMaker(fps, idle=idle, seed=seed, closure_hold=closure_hold(float(fps)), fields=False)
        self.fps = self.maker.fps
        from pocketsphinx import Vad

        self.vad = Vad(VAD_MODE, RATE, VAD_FRAME)
        self.resampler = Resampler(self.rate, RATE)
        self.hop = int(round(HOP * RATE))
        self.decoders = [_decoder() for _ in range(int(round(WINDOW / HOP)))]
        for d in self.decoders:  # all windows before the K-th start at the first sample
            d.start_utt()
        self.fed = 0  # 16 kHz samples fed in all (skipped ones too)
        self.restart = 0  # 16 kHz samples: where the decoders last started afresh (0, or the end of a skip)
        self.skipped = 0  # 16 kHz samples skipped in all
        self.skipped_in = 0  # samples at ``rate`` skipped in all (the 16 kHz count follows their total)
        self.stale_filter = False  # the resampler's state is of the audio before a skip
        self.committed = 0.0  # s: phones before this are final
        self.open: list | None = None  # [viseme, start, end] of the span being spoken
        self.voiced = np.zeros(0, bool)  # per 10 ms from voiced_from: the detector's verdicts
        self.voiced_from = 0
        self.vad_tail = np.zeros(0, np.int16)  # 16 kHz samples not yet a whole detector frame
        self.pitch_context = np.zeros(CONTEXT)  # the audio before the new frames, for their pitch
        self.cents = np.zeros(0)  # the pitch (cents; NaN: unvoiced) of the latest frames
        self.music_left = 0  # frames still held as music after a held note
        self.held = np.zeros(0, bool)  # per 10 ms, the last second: pitch as STEADY_SECONDS before
        self.sung = np.zeros(0, bool)  # per 10 ms, the last second: periodic
        self.music = np.zeros(0, bool)  # per 10 ms, as voiced: music heard
        self.spans = 0  # spans begun (for tests and the benchmark)
        self.log: list[list] | None = [] if keep_spans else None
        self.rng = np.random.default_rng(seed)

    # ---- input -------------------------------------------------------------------------------
    def feed(self, chunk: bytes | np.ndarray) -> np.ndarray:
        """Take the next audio and return the frames that became due, (n, 68) (n may be 0)."""
        if self.stale_filter:
            self.resampler, self.stale_filter = Resampler(self.rate, RATE), False
        samples = self.resampler(_samples(chunk))
        pos = 0
        while pos < len(samples):
            boundary = (self.fed // self.hop + 1) * self.hop  # the next window's end, in 16 kHz samples
            piece = samples[pos:pos + boundary - self.fed]
            self._hear(piece)
            pos += len(piece)
            if self.fed == boundary:
                self._window_done(boundary // self.hop)
        return self._emit(self.fed / RATE - self.latency)

    def skip(self, chunk: bytes | np.ndarray) -> np.ndarray:
        """Pass over the next audio without listening to it, and return the frames that became due.

        Why: a listener that cannot keep up (a machine too busy) would fall further behind the voice for
        the rest of the session; skipping what it is late with costs nothing and brings it back. The
        mouth rests over the skipped audio (the span being spoken closes where the commits had reached),
        and the decoders start afresh after it, as at the start of a session."""
        n_in = len(_samples(chunk))
        if not n_in:
            return np.zeros((0, N_FAPS))
        self.skipped_in += n_in
        n = int(round(self.skipped_in * RATE / self.rate)) - self.skipped  # no rounding piles up over the chunks
        self.stale_filter = self.rate != RATE
        for d in self.decoders:
            d.end_utt()  # what the windows heard since the last commit is dropped with the gap
            d.start_utt()
        self._close(self.committed)
        self._unheard(n)
        self.fed += n
        self.restart = self.fed
        self.skipped += n
        self.committed = self.fed / RATE
        return self._emit(self.fed / RATE - self.latency)

    def _unheard(self, n: int) -> None:
        """The voice and pitch detectors' state after ``n`` samples not heard: unvoiced frames, no pitch."""
        whole, part = divmod(len(self.vad_tail) + n, int(round(VAD_FRAME * RATE)))
        self._verdicts(np.zeros(whole, bool), np.zeros(whole, bool))
        self.vad_tail = np.zeros(part, np.int16)
        self.pitch_context = np.zeros(CONTEXT)
        self.cents = np.full_like(self.cents, np.nan)
        self.held = np.zeros_like(self.held)
        self.sung = np.zeros_like(self.sung)
        self.music_left = 0

    def flush(self) -> np.ndarray:
        """The end of the audio: decode what is left, close the last span and return every frame up to
        the end of the audio fed (the last ones at once, without waiting ``latency``)."""
        if self.fed % self.hop or not self.fed:
            self._window_done(self.fed // self.hop + 1, final=True)
        self._close(self.fed / RATE)
        return self.maker.finish(max(self.fed / RATE, 1 / self.fps)).values

    @property
    def timings(self) -> list:
        """The viseme spans so far as :class:`~.utterance.Timing` (``keep_spans`` only)."""
        from mpeg4fa.speech.utterance import Timing

        if self.log is None:
            raise ValueError("LiveLipSync(keep_spans=True) keeps the spans")
        return [Timing("", v, a, b) for v, a, b in self.log]

    @property
    def frames_out(self) -> int:
        """Frames emitted so far."""
        return self.maker.next

    # ---- recognition -------------------------------------------------------------------------
    def _hear(self, piece: np.ndarray) -> None:
        """16 kHz samples to every decoder (each is inside its window's utterance) and the voice detector."""
        if not len(piece):
            return
        y = np.clip(np.rint(piece.astype(np.float64) + self.rng.standard_normal(len(piece))), -32768, 32767)
        data = y.astype("<i2").tobytes()  # one LSB of noise: digital silence has no log energy
        for d in self.decoders:
            d.process_raw(data, full_utt=False)
        self._listen(y.astype(np.int16))
        self.fed += len(piece)

    def _window_done(self, i: int, final: bool = False) -> None:
        """Window ``i`` (samples ``(i - K) * hop .. i * hop``, K decoders) ended: its decoder's phones are
        committed up to ``SETTLE`` before its end, and it starts window ``i + K``."""
        k = len(self.decoders)
        d = self.decoders[i % k]
        d.end_utt()
        t0 = max(self.restart, (i - k) * self.hop) / RATE  # where this decoder's utterance began
        phones = []
        for seg in d.seg() or ():
            a = t0 + seg.start_frame * _HOP_10MS + (OFFSET if seg.start_frame else 0.0)
            b = t0 + (seg.end_frame + 1) * _HOP_10MS + OFFSET
            phones.append((seg.word, a, b))
        end = self.fed / RATE
        self._commit(phones, end if final else end - SETTLE)
        if not final:
            d.start_utt()

    def _listen(self, y: np.ndarray) -> None:
        """The voice detector's verdict on each whole 10 ms of the 16 kHz samples heard (the newest kept)."""
        n = int(round(VAD_FRAME * RATE))
        buf = np.concatenate([self.vad_tail, y])
        frames = len(buf) // n
        verdicts = np.fromiter((self.vad.is_speech(buf[k * n:(k + 1) * n].tobytes()) for k in range(frames)),
                               bool, frames)
        if frames:
            verdicts &= flatness(buf[:frames * n].reshape(frames, n)) < FLAT
            music = self._notes(buf[:frames * n], frames)
            verdicts &= ~music
        else:
            music = np.zeros(0, bool)
        self.vad_tail = buf[frames * n:]
        self._verdicts(verdicts, music)

    def _verdicts(self, voiced: np.ndarray, music: np.ndarray) -> None:
        """Add the verdicts of the next 10 ms frames, keeping the newest :data:`VERDICTS_KEPT`."""
        self.voiced = np.concatenate([self.voiced, voiced])
        self.music = np.concatenate([self.music, music])
        drop = max(0, len(self.voiced) - VERDICTS_KEPT)
        if drop:
            self.voiced, self.music, self.voiced_from = self.voiced[drop:], self.music[drop:], self.voiced_from + drop

    def _notes(self, y: np.ndarray, frames: int) -> np.ndarray:
        """Which of the new 10 ms frames ``y`` holds are music: a pitch held within :data:`STEADY_CENTS` for
        :data:`STEADY` s (the recording path's test, :mod:`.listen.voice`, on the frames already heard
        only), and everything for :data:`MUSIC_HOLD` s after such a note. Each frame's pitch is measured on
        the :data:`PITCH_WINDOW` samples that end with it (never past the audio heard), its period the
        shortest lag near the best (:func:`~.listen.voice.lag_peaks`: a pure tone's best lag alone jumps
        between multiples of its period)."""
        from mpeg4fa.speech.listen.voice import LAGS, MUSIC_WINDOW, PERIODIC, STEADY_SECONDS, lag_peaks

        n = int(round(VAD_FRAME * RATE))
        x = np.concatenate([self.pitch_context, y.astype(np.float64) / 32768.0])
        self.pitch_context = x[-CONTEXT:]
        ends = CONTEXT + n * (1 + np.arange(frames))
        windows = x[ends[:, None] - PITCH_WINDOW + np.arange(PITCH_WINDOW)[None, :]]
        scale = RATE // VOICE_RATE
        peak, lag = lag_peaks(windows, LAGS[0] * scale, LAGS[1] * scale, shortest=True)
        cents = np.where(peak >= PERIODIC, 1200 * np.log2(RATE / lag), np.nan)
        history = np.concatenate([self.cents, cents])
        steady = int(round(STEADY / VAD_FRAME))
        # the recording path's share rule (listen.voice._held) on the second before each frame: voiced
        # frames whose pitch matches the one STEADY_SECONDS before, octave slips forgiven (several notes at
        # once make the period jump between them: a chord's notes are not all held every frame)
        lag = int(round(STEADY_SECONDS / VAD_FRAME))
        d = np.abs(history[lag:] - history[:-lag]) % 1200  # NaN (unvoiced) compares False
        held = np.r_[np.zeros(min(lag, len(history)), bool), np.minimum(d, 1200 - d) < HELD_CENTS]
        self.held = np.concatenate([self.held, held[-frames:] if frames else held[:0]])
        self.sung = np.concatenate([self.sung, np.isfinite(cents)])
        span = int(round(MUSIC_WINDOW / VAD_FRAME))
        c_held = np.cumsum(np.r_[0, self.held.astype(np.int32)])
        c_sung = np.cumsum(np.r_[0, self.sung.astype(np.int32)])
        end = len(self.sung) - frames + 1 + np.arange(frames)
        start = np.maximum(end - span, 0)
        n_held, n_sung = c_held[end] - c_held[start], c_sung[end] - c_sung[start]
        shared = (n_sung >= MUSIC_SUNG / VAD_FRAME) & (n_held >= MUSIC_SHARE * n_sung)
        self.held, self.sung = self.held[-span:], self.sung[-span:]
        out = np.zeros(frames, bool)
        for k in range(frames):
            now = len(self.cents) + k
            past = history[max(0, now - steady):now + 1]
            if len(past) == steady + 1 and np.isfinite(past).all():
                d = np.abs(past - past[-1]) % 1200
                if (np.minimum(d, 1200 - d) < HELD_CENTS).all():
                    self.music_left = int(round(MUSIC_HOLD / VAD_FRAME))
            if shared[k]:
                self.music_left = max(self.music_left, int(round(MUSIC_HOLD / VAD_FRAME)))
            if self.music_left > 0:
                out[k] = True
                self.music_left -= 1
        self.cents = history[-max(steady, lag) - 1:]
        return out

    def _is_voiced(self, a: float, b: float) -> bool:
        """Whether most of ``[a, b)`` is voice, or within :data:`REACH` after voice (the consonants that
        close a syllable: a stop's silent closure, a final s; the ones before a vowel would need the audio
        after them, which the latency does not wait for)."""
        i = int(round(a / VAD_FRAME)) - self.voiced_from
        j = max(i + 1, int(round(b / VAD_FRAME)) - self.voiced_from)
        reach = int(round(REACH / VAD_FRAME))
        heard = self.voiced[max(0, i - reach):max(0, j)]
        if not len(heard):
            return False
        near = np.convolve(heard, np.ones(reach + 1), mode="full")[:len(heard)] > 0  # voice within reach before
        near &= ~self.music[max(0, i - reach):max(0, j)]  # not the reach of a note's onset into the note
        part = near[len(heard) - (j - max(i, 0)):] if j > max(i, 0) else near[-1:]
        return bool(len(part)) and part.mean() >= 0.5

    def _commit(self, phones: list[tuple[str, float, float]], upto: float) -> None:
        """The phones of ``[committed, upto)`` become the face's: spans begun, grown or closed."""
        lo = self.committed
        for word, start, end in phones:
            parts = phone_parts(word) or ((VOICE_VISEME, 0.0, 1.0),)
            for viseme, p0, p1 in parts:  # each part over its share of the whole phone, then cut to what is new
                a = max(start + p0 * (end - start), lo)
                b = min(start + p1 * (end - start), upto)
                if b - a <= 1e-6:
                    continue
                if not self._is_voiced(a, b):
                    viseme = None
                elif not phone_parts(word):  # voice the loop calls silence
                    viseme = VOICE_VISEME
                self._phase(viseme, a, b)
        self.committed = max(lo, upto)
        if self.open is not None:
            self._grow(self.committed)

    def _phase(self, viseme: str | None, a: float, b: float) -> None:
        if self.open is not None and viseme == self.open[0] and abs(self.open[2] - a) < 1e-6:
            self._grow(b)
            return
        self._close(a)
        if viseme is None:
            return
        self.open = [viseme, a, b]
        self.spans += 1
        if self.log is not None:
            self.log.append(self.open)  # the same list: it grows with the span
        # the move in takes its lag as from a phone of full length (LAG); its real end follows as it grows
        (phase,) = _checked_spans([VisemeSpan(viseme, a, max(b, a + LAG / LAG_SHARE))])
        self.maker.segments += self.maker.moves.add(phase)
        self._grow(b)

    def _grow(self, end: float) -> None:
        """The span being spoken lasts to ``end`` so far (the moves' last phase follows it)."""
        self.open[2] = max(self.open[2], end)
        last = self.maker.moves.last
        self.maker.moves.last = (last[0], self.open[2], last[2], last[3])

    def _close(self, at: float) -> None:
        """The span being spoken ends at ``at``: the move back to rest is known now (the silence after it
        counts as long; a phone soon after starts from where that move has the mouth)."""
        if self.open is not None:
            self._grow(at)
            self.open = None
            self.maker.segments += self.maker.moves.finish()

    # ---- output ------------------------------------------------------------------------------
    def _emit(self, until: float) -> np.ndarray:
        """Frames with times up to ``until`` (s), which the commits must reach ``LEAD`` past."""
        stop = math.floor(round(until * self.fps, 9)) + 1 if until >= 0 else 0
        if stop <= self.maker.next:
            return np.zeros((0, N_FAPS))
        assert (stop - 1) / self.fps <= self.committed - LEAD + 1e-9, "a frame went out before its moves were known"
        return self.maker._frames(stop).values


def flatness(frames: np.ndarray) -> np.ndarray:
    """Spectral flatness of each row of 16 kHz samples over 250-6000 Hz (Hann window): near 0 for a
    voice's harmonics, about 0.56 for white noise."""
    n = frames.shape[1]
    size = 1 << (n - 1).bit_length()
    power = np.abs(np.fft.rfft(frames * np.hanning(n), size, axis=1)) ** 2 + 1e-3
    band = power[:, int(250 * size / RATE):int(6000 * size / RATE)]
    return np.exp(np.log(band).mean(axis=1)) / band.mean(axis=1)


class Resampler:
    """Streaming resampling to the model's rate: a low-pass (8th-order Butterworth at 0.9 x the lower
    Nyquist frequency, its state carried from chunk to chunk) and linear interpolation whose position runs on
    across chunks, so cutting the audio anywhere gives the same samples."""

    def __init__(self, rate: int, target: int) -> None:
        self.rate, self.target, self.step = rate, target, rate / target
        self.pos = 0.0  # the next output sample's position in input samples, from the first kept one
        self.last = np.zeros(0)  # the input sample before the current chunk (for interpolation)
        if rate != target:
            from scipy.signal import butter, sosfilt_zi

            self.sos = butter(8, 0.9 * min(rate, target) / rate, output="sos")
            self.zi = sosfilt_zi(self.sos) * 0.0

    def __call__(self, x: np.ndarray) -> np.ndarray:
        if self.rate == self.target:
            return x
        from scipy.signal import sosfilt

        y, self.zi = sosfilt(self.sos, x.astype(np.float64), zi=self.zi)
        buf = np.concatenate([self.last, y])
        n = max(0, math.floor((len(buf) - 1 - self.pos) / self.step) + 1) if len(buf) else 0
        at = self.pos + self.step * np.arange(n)
        out = np.interp(at, np.arange(len(buf)), buf) if n else np.zeros(0)
        self.pos = self.pos + self.step * n - (len(buf) - 1)
        self.last = buf[-1:]
        return np.clip(np.rint(out), -32768, 32767).astype(np.int16)


def _samples(chunk: bytes | np.ndarray) -> np.ndarray:
    if isinstance(chunk, (bytes, bytearray, memoryview)):
        data = bytes(chunk)
        if len(data) % 2:
            raise ValueError(f"a chunk of s16le PCM has an even number of bytes, not {len(data)}")
        return np.frombuffer(data, "<i2").astype(np.int16)
    x = np.asarray(chunk)
    if x.ndim != 1:
        raise ValueError(f"a chunk is mono samples (n,), not shape {x.shape}")
    if x.dtype == np.int16:
        return x
    if np.issubdtype(x.dtype, np.floating):
        if not np.isfinite(x).all():
            raise ValueError("a chunk holds NaN or infinite samples")
        return np.clip(np.rint(x * 32768.0), -32768, 32767).astype(np.int16)
    raise ValueError(f"a chunk is int16 or float samples, not {x.dtype}")


LIVE_CODING = {"fap_quant": 3}
"""Coding options of the live face: the text path's quantiser (:data:`~.encoder.TEXT_CODING`) without its
search for the cheapest coding, which costs some 50 ms a message (here 3-4 ms for a frame or two)."""


class LiveEncoder:
    """Frames in as they come out of :class:`LiveLipSync`, FBA bits out: each batch a complete fba_object
    (an intra frame, low-level FAPs; a FAP once sent is sent in every later batch, so each decodes on its
    own), its timestamps from 0 (the caller places it at its first frame's time).

    Why whole objects: a player joins the stream at any batch, and a lost or late one costs nothing later.
    A batch of one or two frames at 25 fps takes some 75 bytes (a stream of the whole session would take
    a third of that; the latency is what is bought).
    """

    def __init__(self, fps: float = 25.0) -> None:
        from mpeg4fa.speech.encoder import StreamBuilder

        self.fps = float(fps)
        self.builder = StreamBuilder("low", self.fps, fold=False, compact=False)

    def encode(self, frames: np.ndarray) -> bytes:
        """One fba_object of ``frames`` ((n, 68), n >= 1)."""
        from mpeg4fa.fba import EncodeOptions, encode
        from mpeg4fa.speech.frames import FrameBlock

        values = np.asarray(frames, np.float64)
        if values.ndim != 2 or not len(values):
            raise ValueError(f"frames are (n >= 1, 68) rows, not shape {values.shape}")
        stream = self.builder.build(FrameBlock(0, np.arange(len(values)) / self.fps, values, None, None))
        return encode(stream, EncodeOptions(**LIVE_CODING))
