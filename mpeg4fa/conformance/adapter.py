"""This project's decoder behind the suite's protocol: the first adapter, and the runner's default.

``python -m mpeg4fa.conformance.adapter STREAM OUT.json [--fdp FDP]`` decodes with
:func:`mpeg4fa.fba.decode`, reports the sent fields and the shown values
(:func:`mpeg4fa.decoded.resolve`), and, given an FDP, the feature points of this project's face
engine calibrated to it and posed at every frame. The face engine needs the generic head
(``mpeg4fa model install``); without it feature points are left out, so the runner marks the
feature-point checks "not supported" instead of building the head mid-run. A stream the codec
refuses exits 1 with ``bit N`` on stderr.
"""
from __future__ import annotations

import argparse
import sys
import warnings
from functools import lru_cache
from pathlib import Path

import numpy as np

from mpeg4fa.conformance.protocol import DecoderOutput, InProcessDecoder, Rejected, write_output
from mpeg4fa.decoded import ClampWarning, resolve
from mpeg4fa.fba import FapStream, FbaError, decode


def sent_fields(stream: FapStream) -> dict[str, np.ndarray]:
    """The protocol's ``sent`` block: what each frame carried, before any decoder rule."""
    return {"mask": stream.fap_mask.astype(np.int64), "values": stream.fap_values.astype(np.int64),
            "viseme": stream.viseme.astype(np.int64), "expression": stream.expression.astype(np.int64)}


def decode_stream(path: Path) -> FapStream:
    """The decoded stream; :class:`Rejected` (with the fault's bit and the frames before it) on a fault."""
    try:
        return decode(Path(path))
    except FbaError as exc:
        partial = None
        if exc.partial is not None and len(exc.partial):
            partial = stream_output(exc.partial)
        raise Rejected(str(exc), exc.bit_offset, partial) from None


def shown(stream: FapStream) -> np.ndarray:
    """What the decoder shows (clamps are the decoder's business here, not a warning for the suite)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ClampWarning)
        return resolve(stream)


def stream_output(stream: FapStream, values: np.ndarray | None = None) -> DecoderOutput:
    """The protocol's output for a decoded stream (without feature points)."""
    return DecoderOutput(stream.timestamps.astype(np.float64), shown(stream) if values is None else values,
                         sent_fields(stream))


def head_installed() -> bool:
    """Whether the face engine's generic head is built (checked without building it)."""
    from mpeg4fa.face import asset

    return asset.is_installed()


@lru_cache(maxsize=8)
def _calibrated(fdp_path: str, mtime: float):
    from mpeg4fa.face import FaceModel
    from mpeg4fa.fdp import load_fdp

    return FaceModel.default(auto_install=False).calibrate(load_fdp(fdp_path))


def face_feature_points(fdp: Path, values: np.ndarray) -> tuple[tuple[str, ...], np.ndarray]:
    """Labels and ``(n, 84, 3)`` positions of the face engine's feature points, calibrated to ``fdp``
    and posed by each row of ``values``."""
    model = _calibrated(str(fdp), Path(fdp).stat().st_mtime)
    positions = np.stack([model.pose_values(row).feature_points for row in values]) if len(values) else \
        np.zeros((0, len(model.mesh.fp_labels), 3))
    return tuple(model.mesh.fp_labels), positions


def decode_for_suite(stream: Path, fdp: Path | None = None, *, feature_points: bool | None = None) -> DecoderOutput:
    """The adapter's answer for one vector. ``feature_points``: None = when an FDP is given and the
    head is installed; True/False forces it."""
    decoded = decode_stream(stream)
    output = stream_output(decoded)
    want = (fdp is not None and head_installed()) if feature_points is None else feature_points
    if want and fdp is not None:
        output.fp_labels, output.fp_positions = face_feature_points(fdp, output.shown)
    return output


def in_process() -> InProcessDecoder:
    """This project's decoder as the runner's default (no subprocess)."""
    return InProcessDecoder(decode_for_suite, name="mpeg4fa (in-process)")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m mpeg4fa.conformance.adapter",
                                     description="Decode STREAM for the conformance suite into OUT (.json or .csv).")
    parser.add_argument("stream", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--fdp", type=Path)
    args = parser.parse_args(argv)
    try:
        output = decode_for_suite(args.stream, args.fdp)
    except Rejected as exc:
        print(f"rejected: {exc.message}" + ("" if exc.bit_offset is None or "bit" in exc.message
                                            else f" at bit {exc.bit_offset}"), file=sys.stderr)
        return 1
    except Exception as exc:  # noqa: BLE001 - anything else is a crash, exit status 3 (1 means "rejected")
        print(f"crash: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 3
    write_output(output, args.out)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
