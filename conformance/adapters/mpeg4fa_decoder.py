#!/usr/bin/env python3
"""This project's decoder as an external command of the conformance protocol: an example adapter.

    mpeg4fa conform --decoder "python3 conformance/adapters/mpeg4fa_decoder.py"

The runner calls it once per vector as ``mpeg4fa_decoder.py STREAM OUT.json [--fdp FDP]``. It uses
only the package's public API (``mpeg4fa.fba.decode``, ``mpeg4fa.decoded.resolve``), the way a
Python program embedding the decoder would, and writes the protocol's answer itself:

* ``timestamps`` (seconds, float: no ``timestamp_resolution`` needed) and ``shown`` (68 values a
  frame, FAP 1/2 columns 0) are required; ``sent`` (what each frame carried) is optional, and it
  reports it so that the suite's exact ``sent`` checks run. It leaves feature points out (the
  in-process default adds them when the generic head is installed).
* exit 0: decoded; exit 1: the stream is refused, ``bit N`` on stderr where the fault is, and the
  frames decoded before it written to OUT; exit 3: anything else (the runner's "crash").

The output is written to a temporary name and moved into place, so a killed run leaves no half file.
"""
import json
import os
import sys
import warnings


def answer(stream) -> dict:
    """The protocol's JSON object for a decoded ``FapStream``."""
    from mpeg4fa.decoded import ClampWarning, resolve

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ClampWarning)  # a face's clamp is not the suite's business
        shown = resolve(stream)
    return {"timestamps": stream.timestamps.astype(float).tolist(),
            "shown": shown.astype(float).tolist(),
            "sent": {"mask": stream.fap_mask.astype(int).tolist(), "values": stream.fap_values.astype(int).tolist(),
                     "viseme": stream.viseme.astype(int).tolist(), "expression": stream.expression.astype(int).tolist()}}


def write(doc: dict, out: str) -> None:
    tmp = f"{out}.tmp"
    with open(tmp, "w", encoding="utf-8") as fh:
        json.dump(doc, fh)
    os.replace(tmp, out)


def main(argv: list) -> int:
    if len(argv) not in (2, 4) or (len(argv) == 4 and argv[2] != "--fdp"):
        print("usage: mpeg4fa_decoder.py STREAM OUT.json [--fdp FDP]", file=sys.stderr)
        return 3
    stream_path, out = argv[0], argv[1]
    try:
        from mpeg4fa.fba import FbaError, decode
    except ImportError as exc:
        print(f"crash: mpeg4fa is not importable here: {exc}", file=sys.stderr)
        return 3
    try:
        with open(stream_path, "rb") as fh:
            stream = decode(fh.read())
    except FbaError as exc:
        if exc.partial is not None and len(exc.partial):
            write(answer(exc.partial), out)  # the frames before the fault
        where = f" (bit {exc.bit_offset})" if exc.bit_offset is not None else ""
        print(f"refused: {exc}{where}", file=sys.stderr)
        return 1
    except Exception as exc:  # noqa: BLE001 - any other failure is a crash for the runner (exit 3)
        print(f"crash: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 3
    write(answer(stream), out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
