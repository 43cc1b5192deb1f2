"""What a stream holds, as plain data for people (``mpeg4fa info``) and programs (``--json``)."""
from __future__ import annotations

import numpy as np

from .stream import BODY, FACE, FapStream

_OBJECT = {FACE: "face", BODY: "body", FACE | BODY: "face+body"}


def describe(stream: FapStream, n_bytes: int | None = None) -> dict:
    """Header, frames, timing, masks and bit rate of ``stream`` (bits from the decoder, or ``n_bytes``)."""
    n = len(stream)
    duration = stream.duration
    first = stream.first_params
    objects = sorted({_OBJECT.get(int(m), str(int(m))) for m in np.unique(stream.object_mask)})
    info: dict = {
        "frames": n,
        "fps": round(stream.fps, 6),
        "duration_s": round(duration, 6),
        "object": objects[0] if len(objects) == 1 else objects,
        "intra_frames": sorted(stream.intra),
        "skipped_frames": int(stream.skip.sum()),
        "plane_start_codes": int(np.count_nonzero(stream.start_code)),
        "time_codes": sum(1 for p in stream.intra.values() if p.time_code is not None),
    }
    if first is not None:
        fr = first.frame_rate
        info["frame_rate_field"] = None if fr is None else {
            "frame_rate": fr.frame_rate, "seconds": fr.seconds, "frequency_offset": fr.frequency_offset}
        if first.face is not None:
            info["fap_quant"] = first.face.quant
            info["fap_mask_types"] = list(first.face.mask_types)
        if first.body is not None:
            info["bap_quant"] = first.body.quant
            info["bap_mask_types"] = list(first.body.mask_types)
    sent = np.flatnonzero(stream.fap_mask.any(axis=0)) + 1
    info["faps_sent"] = sent.tolist()
    info["baps_sent"] = int(np.count_nonzero(stream.bap_mask.any(axis=0)))
    if stream.fap_mask[:, 0].any():
        info["visemes_used"] = sorted(set(np.unique(stream.viseme[stream.fap_mask[:, 0], :2]).tolist()))
    if stream.fap_mask[:, 1].any():
        info["expressions_used"] = sorted(set(np.unique(stream.expression[stream.fap_mask[:, 1]][:, [0, 2]]).tolist()))
    total_bits = int(stream.bits.sum()) if stream.bits.any() else None
    if n_bytes is not None:
        info["bytes"] = n_bytes
        total_bits = n_bytes * 8
    if total_bits is not None and n:
        per_frame = stream.bits if stream.bits.any() else np.full(n, total_bits / n)
        info["bits_per_frame"] = {"mean": round(float(per_frame.mean()), 2), "min": int(per_frame.min()),
                                  "max": int(per_frame.max()), "intra_mean": round(float(
                                      per_frame[sorted(stream.intra)].mean()), 2) if stream.intra else None}
        info["kbit_per_s"] = round(total_bits / duration / 1000.0, 3) if duration > 0 else None
    return info
