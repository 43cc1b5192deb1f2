"""A small synthetic FAP sequence: something to encode when no stream is at hand.

It is made here, by code, so that the demo and the tests need no file from
elsewhere: a face saying six visemes with a jaw and lips that follow them, one
blink, a slight nod and a smile that grows.
"""
from __future__ import annotations

import numpy as np

from .. import spec
from .stream import FapStream

# FAP numbers used below, by their names in spec/faps.csv
_OPEN_JAW, _LOWER_T_MIDLIP, _RAISE_B_MIDLIP = (spec.FAP_BY_NAME[n].number for n in (
    "open_jaw", "lower_t_midlip", "raise_b_midlip"))
_STRETCH_L_CORNER, _STRETCH_R_CORNER = (spec.FAP_BY_NAME[n].number for n in (
    "stretch_l_cornerlip", "stretch_r_cornerlip"))
_CLOSE_T_L_EYELID, _CLOSE_T_R_EYELID = (spec.FAP_BY_NAME[n].number for n in ("close_t_l_eyelid", "close_t_r_eyelid"))
_RAISE_L_CORNER_O, _RAISE_R_CORNER_O = (spec.FAP_BY_NAME[n].number for n in (
    "raise_l_cornerlip_o", "raise_r_cornerlip_o"))
_HEAD_PITCH = spec.FAP_BY_NAME["head_pitch"].number
_SENT = (_OPEN_JAW, _LOWER_T_MIDLIP, _RAISE_B_MIDLIP, _STRETCH_L_CORNER, _STRETCH_R_CORNER,
         _CLOSE_T_L_EYELID, _CLOSE_T_R_EYELID, _HEAD_PITCH, _RAISE_L_CORNER_O, _RAISE_R_CORNER_O)

# (viseme, frames) for "hello there", roughly: h-e-l-o  th-e-r
_CODE = {v.name: v.number for v in spec.VISEMES}
_VISEMES = tuple((_CODE[name], frames) for name, frames in (
    ("none", 5), ("E", 5), ("nn", 4), ("oh", 6), ("none", 3), ("TH", 4), ("E", 5), ("RR", 5), ("none", 8)))
_OPEN = tuple(_CODE[name] for name in ("E", "oh", "AA"))  # visemes with the mouth open wide
_JOY = next(e.number for e in spec.EXPRESSIONS if e.name == "joy")


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
    s.viseme[:, 2] = spec.FULL_INTENSITY
    opening = np.where(np.isin(vis, _OPEN), 1.0, np.where(vis == 0, 0.0, 0.45))
    opening = np.convolve(opening, np.ones(3) / 3, mode="same")  # coarticulation, crudely
    v = s.fap_values
    v[:, _OPEN_JAW - 1] = np.round(opening * 420)
    v[:, _LOWER_T_MIDLIP - 1] = np.round(-opening * 60)
    v[:, _RAISE_B_MIDLIP - 1] = np.round(-opening * 300)
    smile = np.clip(t / seconds, 0, 1)
    s.expression[:, 0] = _JOY
    s.expression[:, 1] = np.round(smile * 40)
    v[:, _STRETCH_L_CORNER - 1] = v[:, _STRETCH_R_CORNER - 1] = np.round(smile * 120)
    v[:, _RAISE_L_CORNER_O - 1] = v[:, _RAISE_R_CORNER_O - 1] = np.round(smile * 100)
    blink = np.exp(-(((t - seconds * 0.6) * fps / 2.0) ** 2))
    v[:, _CLOSE_T_L_EYELID - 1] = v[:, _CLOSE_T_R_EYELID - 1] = np.round(blink * 1000)
    v[:, _HEAD_PITCH - 1] = np.round(np.sin(2 * np.pi * t / seconds) * 17000)  # about 0.17 rad
    return s
