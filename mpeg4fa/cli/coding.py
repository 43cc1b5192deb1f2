"""The coding flags of ``encode`` (quantiser, intra period, frame rate, masks...) and the options they make.

Its own module so that both of encode's paths, a stream re-encoded (:mod:`.codec`) and text
spoken (:mod:`.speech`), read them without importing each other.
"""
from __future__ import annotations

import argparse
import dataclasses

from ..fba import EncodeOptions
from ..spec import N_FAP_GROUPS
from . import options


def coding_flags(p: argparse.ArgumentParser) -> None:
    """Add the flags that set :class:`EncodeOptions` fields."""
    p.add_argument("--quant", type=options.quant, metavar="0-31", help="fap_quant: 0 = exact, larger = coarser "
                                                                      "(default 1)")
    p.add_argument("--bap-quant", type=options.quant, metavar="0-31", help="bap_quant for body data (default 1)")
    p.add_argument("--intra-period", type=options.period, metavar="K",
                   help="an intra frame every K frames (0 = first only)")
    p.add_argument("--fps", type=options.fps, help="frame rate to send, 0 < fps < 256 (default: the input's; "
                                                   "25 for text)")
    p.add_argument("--mask-types", type=options.mask_types, metavar="T,T,...",
                   help=f"{N_FAP_GROUPS} FAP group mask types: 0 none, 1 hold unsent, 2 interpolate unsent, 3 all")
    p.add_argument("--start-codes", action=argparse.BooleanOptionalAction, default=None,
                   help="send a plane start code before every intra plane")
    p.add_argument("--skip-repeats", action="store_true", help="send repeated frames as skip counts")
    p.add_argument("--time-codes", action="store_true", help="send a time code in every intra header")
    p.add_argument("--optimize", action="store_true",
                   help="smallest stream with the same decoded values (tight ranges, repeats skipped)")


def coding_options(args: argparse.Namespace, default: EncodeOptions | None) -> EncodeOptions | None:
    """``default`` with the coding flags given on the command line put over it (None: none given)."""
    chosen = {"fap_quant": args.quant, "bap_quant": args.bap_quant, "intra_period": args.intra_period,
              "fps": args.fps, "mask_types": args.mask_types, "start_codes": args.start_codes,
              "skip_repeats": args.skip_repeats or None, "time_codes": args.time_codes or None,
              "optimize": args.optimize or None}
    given = {k: v for k, v in chosen.items() if v is not None}
    if not given:
        return default
    return dataclasses.replace(default, **given) if default is not None else EncodeOptions(**given)
