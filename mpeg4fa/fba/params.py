"""Quantisation, ranges, prediction and models of the arithmetic-coded parameters.

Both directions share one object per group of parameters: it knows, since the
last intra header, which parameters are masked, their quantiser steps, their I
and P ranges (in quantised units) and the previous reconstructed values, and so
maps values to symbols (encoder) and symbols to values (decoder) with the same
closed-loop prediction.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from .. import spec
from .arith import AdaptiveModel
from .errors import FbaError
from .stream import N_BAPS, N_FAPS, PartParams

RANGE_DELTA = 60
"""A 5-bit range code c stands for c * 60 quantised units (before division by the quantiser)."""


def quantise(x: np.ndarray, qstep: np.ndarray) -> np.ndarray:
    """The reference quantiser: 0 when |x| <= q/2 (integer halves), else round(|x|/q) half up; sign kept."""
    x = np.asarray(x, dtype=np.int64)
    q = np.maximum(qstep, 1)
    half = qstep // 2
    level = np.where(np.abs(x) <= half, 0, (np.abs(x) + half) // q)
    return np.where(qstep == 0, x, np.sign(x) * level)


def dequantise(level: np.ndarray, qstep: np.ndarray) -> np.ndarray:
    return np.where(qstep == 0, level, level * qstep)


@dataclass(frozen=True)
class PartSpec:
    """What differs between the face and the body part: sizes, groups, steps, default ranges."""

    name: str
    label: str
    n: int
    mask_groups: tuple[tuple[int, ...], ...]
    range_groups: tuple[tuple[int, ...], ...]
    quant_step: np.ndarray
    step_multiplier: Callable[[int], int]
    default_i: np.ndarray | None = None
    default_p: np.ndarray | None = None

    @property
    def order(self) -> np.ndarray:
        """Arithmetic-coding order of the parameters (groups in order, members in order)."""
        return np.array([i for g in self.range_groups for i in g], dtype=np.int64)


FACE = PartSpec(
    name="face", label="FAP", n=N_FAPS,
    mask_groups=tuple(tuple(range(a, b)) for a, b in spec.FAP_GROUP_SLICES),
    range_groups=tuple(tuple(range(a, b)) for a, b in spec.FAP_GROUP_SLICES[1:]),
    quant_step=spec.QUANT_STEP.astype(np.int64),
    step_multiplier=lambda q: q,
    default_i=spec.I_MAX_DEFAULT.astype(np.int64),
    default_p=spec.P_MAX_DEFAULT.astype(np.int64),
)

BODY = PartSpec(
    name="body", label="BAP", n=N_BAPS,
    mask_groups=spec.BAP_GROUPS, range_groups=spec.BAP_GROUPS,
    quant_step=spec.BAP_QUANT_STEP.astype(np.int64),
    step_multiplier=lambda q: int(spec.BAP_PRED_SCALE[q]),
)


class _Coder:
    """Symbols <-> values for the masked parameters ``idx`` of one segment."""

    idx: np.ndarray
    qstep: np.ndarray
    imin: np.ndarray
    isize: np.ndarray
    pmin: np.ndarray
    psize: np.ndarray
    prev: np.ndarray
    label: Callable[[int], str]

    def _models(self) -> None:
        self.intra_models = [int(s) for s in self.isize]
        self.p_models = None  # made when a P plane first needs them (the compiled path never does)

    def models(self, intra: bool) -> list:
        if intra:
            return self.intra_models
        if self.p_models is None:
            self.p_models = [AdaptiveModel(int(s)) for s in self.psize]
        return self.p_models

    def decode(self, symbols: Sequence[int], intra: bool) -> np.ndarray:
        level = np.asarray(symbols, dtype=np.int64) + (self.imin if intra else self.pmin)
        values = dequantise(level, self.qstep)
        if not intra:
            values = values + self.prev[self.idx]
        self.prev[self.idx] = values
        return values

    def encode(self, values: np.ndarray, intra: bool, frame: int) -> list[int]:
        target = np.asarray(values, dtype=np.int64)[self.idx]
        diff = target if intra else target - self.prev[self.idx]
        level = quantise(diff, self.qstep)
        symbols = level - (self.imin if intra else self.pmin)
        size = self.isize if intra else self.psize
        bad = np.flatnonzero((symbols < 0) | (symbols >= size))
        if bad.size:
            k = int(bad[0])
            raise FbaError(self.range_message(k, int(diff[k]), int(level[k]), intra), frame=frame)
        recon = dequantise(level, self.qstep)
        self.prev[self.idx] = recon if intra else self.prev[self.idx] + recon
        return symbols.tolist()


    def range_message(self, k: int, diff: int, level: int, intra: bool) -> str:
        """Why parameter ``k`` (in coding order) cannot be coded: its level is outside its model."""
        low = int(self.imin[k] if intra else self.pmin[k])
        size = int(self.isize[k] if intra else self.psize[k])
        kind = "intra value" if intra else "change from the previous frame"
        return (f"{self.label(int(self.idx[k]))}: {kind} {diff} quantises to level {level}, outside its coded "
                f"range {low}..{low + size - 1}; use a coarser quantiser, wider ranges or more intra frames")


class ValueCoder(_Coder):
    """FAPs 3..68 of the face part, or the BAPs of the body part."""

    def __init__(self, part: PartSpec) -> None:
        self.part = part
        self.ranges = np.zeros((4, part.n), dtype=np.int64)  # I max, I min, P max, P min
        self.defaults_applied = False
        self.prev = np.zeros(part.n, dtype=np.int64)
        self.params: PartParams | None = None
        self.label = lambda i: f"{part.label} {i + 1}"

    def start_intra(self, params: PartParams) -> None:
        """Apply an intra header: default ranges (first time only), new ranges, new models."""
        part = self.part
        step = part.step_multiplier(params.quant)
        scaler = step or 1
        if not self.defaults_applied and part.default_i is not None:
            for k, default in ((0, part.default_i), (2, part.default_p)):
                rounded = -(-default // RANGE_DELTA) * RANGE_DELTA
                self.ranges[k] = rounded // scaler
                self.ranges[k + 1] = -self.ranges[k]
        self.defaults_applied = True
        for k in range(4):
            if params.ranges.flags[k]:
                m = params.mask
                magnitude = params.ranges.codes[k, m].astype(np.int64) * RANGE_DELTA // scaler
                self.ranges[k, m] = magnitude if k % 2 == 0 else -magnitude
        order = part.order
        self.idx = order[params.mask[order]]
        self.qstep = part.quant_step[self.idx] * step
        self.imin = self.ranges[1, self.idx]
        self.isize = self.ranges[0, self.idx] - self.imin + 1
        self.pmin = self.ranges[3, self.idx]
        self.psize = self.ranges[2, self.idx] - self.pmin + 1
        self.params = params
        self._models()


_FIELDS = spec.HIGH_LEVEL_FIELDS


class FieldCoder(_Coder):
    """The fields of FAP 1 (viseme) or FAP 2 (expression), whose ranges are fixed."""

    def __init__(self, fap: int) -> None:
        self.fields = [k for k, f in enumerate(_FIELDS) if f.fap == fap]
        self.idx = np.arange(len(self.fields))
        self.quantised = np.array([_FIELDS[k].quantised for k in self.fields])
        self.i_max = np.array([_FIELDS[k].i_max for k in self.fields], dtype=np.int64)
        self.imin = np.array([_FIELDS[k].i_min for k in self.fields], dtype=np.int64)
        self.p_max = np.array([_FIELDS[k].p_max for k in self.fields], dtype=np.int64)
        self.pmin = np.array([_FIELDS[k].p_min for k in self.fields], dtype=np.int64)
        self.prev = np.zeros(len(self.fields), dtype=np.int64)
        self.qstep = np.zeros(len(self.fields), dtype=np.int64)
        names = [f"FAP {fap} {_FIELDS[k].field}" for k in self.fields]
        self.label = lambda i: names[i]

    def start_intra(self, fap_quant: int) -> None:
        """Blend and intensity ranges become (63 + q/2) / q; with q = 0 they keep their last value."""
        if fap_quant:
            top = (spec.FULL_INTENSITY + fap_quant // 2) // fap_quant
            self.i_max[self.quantised] = top
            self.p_max[self.quantised] = top
            self.pmin[self.quantised] = -top
        self.qstep = np.where(self.quantised, fap_quant, 0)
        self.isize = self.i_max - self.imin + 1
        self.psize = self.p_max - self.pmin + 1
        self._models()

    def check_selects(self, values: np.ndarray, bit_offset: int, frame: int) -> None:
        """Selects must name a viseme 0..14 / expression 0..6."""
        for k in np.flatnonzero(~self.quantised):
            v = int(values[k])
            if not 0 <= v <= self.select_max(int(k)):
                raise FbaError(self.select_message(int(k), v), bit_offset, frame)

    def select_max(self, k: int) -> int:
        """The largest value field ``k`` may decode to: 14 (viseme) / 6 (expression) for a select, -1 otherwise."""
        return -1 if self.quantised[k] else int(_FIELDS[self.fields[k]].i_max)

    def select_message(self, k: int, value: int) -> str:
        return f"{self.label(k)} decodes to {value}, outside 0..{self.select_max(k)}"
