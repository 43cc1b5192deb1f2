"""A small synthetic FAP sequence: something to encode when no stream is at hand.

It is made here, by code, so that the demo and the tests need no file from
elsewhere: a face saying six visemes with a jaw and lips that follow them, one
blink, a slight nod and a smile that grows.
"""
from __future__ import annotations

import numpy as np

from .stream import FapStream

# FAP numbers used below (see spec/faps.csv)
_OPEN_JAW, _LOWER_T_MIDLIP, _RAISE_B_MIDLIP = 3, 4, 5
_STRETCH_L_CORNER, _STRETCH_R_CORNER = 6, 7
_CLOSE_T_L_EYELID, _CLOSE_T_R_EYELID = 19, 20
_RAISE_L_CORNER_O, _RAISE_R_CORNER_O = 59, 60
_HEAD_PITCH = 48
_SENT = (_OPEN_JAW, _LOWER_T_MIDLIP, _RAISE_B_MIDLIP, _STRETCH_L_CORNER, _STRETCH_R_CORNER,
         _CLOSE_T_L_EYELID, _CLOSE_T_R_EYELID, _HEAD_PITCH, _RAISE_L_CORNER_O, _RAISE_R_CORNER_O)

# (viseme, frames) for "hello there", roughly: h-e-l-o  th-e-r
_VISEMES = ((0, 5), (11, 5), (8, 4), (13, 6), (0, 3), (3, 4), (11, 5), (9, 5), (0, 8))


def demo_stream(fps: float = 25.0, seconds: float = 4.0) -> FapStream:
    """A face-only stream with FAP 1, FAP 2 and ten low-level FAPs, on every frame."""
    n = int(round(fps * seconds))
    s = FapStream.empty(n)
    s.source_fps = fps
    t = np.arange(n) / fps
    s.timestamps = t
    cycle = np.concatenate([np.full(length, v) for v, length in _VISEMES])
    vis = np.resize(cycle, n)
    s.fap_mask[:, 0] = s.fap_mask[:, 1] = True
    s.fap_mask[:, [f - 1 for f in _SENT]] = True
    s.viseme[:, 0] = vis
    s.viseme[:, 1] = np.roll(vis, 1)
    s.viseme[:, 2] = 63
    opening = np.where(np.isin(vis, (11, 13, 10)), 1.0, np.where(vis == 0, 0.0, 0.45))
    opening = np.convolve(opening, np.ones(3) / 3, mode="same")  # coarticulation, crudely
    v = s.fap_values
    v[:, _OPEN_JAW - 1] = np.round(opening * 420)
    v[:, _LOWER_T_MIDLIP - 1] = np.round(-opening * 60)
    v[:, _RAISE_B_MIDLIP - 1] = np.round(-opening * 300)
    smile = np.clip(t / seconds, 0, 1)
    s.expression[:, 0] = 1            # joy
    s.expression[:, 1] = np.round(smile * 40)
    v[:, _STRETCH_L_CORNER - 1] = v[:, _STRETCH_R_CORNER - 1] = np.round(smile * 120)
    v[:, _RAISE_L_CORNER_O - 1] = v[:, _RAISE_R_CORNER_O - 1] = np.round(smile * 100)
    blink = np.exp(-(((t - seconds * 0.6) * fps / 2.0) ** 2))
    v[:, _CLOSE_T_L_EYELID - 1] = v[:, _CLOSE_T_R_EYELID - 1] = np.round(blink * 1000)
    v[:, _HEAD_PITCH - 1] = np.round(np.sin(2 * np.pi * t / seconds) * 17000)  # about 0.17 rad
    return s
