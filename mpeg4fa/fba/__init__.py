"""The FBA bitstream codec (ISO/IEC 14496-2 fba_object): decode and encode FAP/BAP streams.

Layers, bottom up: ``bits`` (bit reader/writer, start codes) -> ``arith`` (adaptive
arithmetic coder) -> ``syntax`` and ``params`` (headers, ranges, quantisation,
prediction) -> ``decoder`` / ``encoder`` (planes and frames) -> ``stream`` (the
data model). ``spec/SYNTAX.md`` describes the bitstream as implemented.
"""
from .decoder import decode, iter_decode
from .errors import FbaError, UnsupportedFeature
from .stream import CodingParams, FapStream, Frame, FrameRate, PartParams, RangeSet, TimeCode

__all__ = ["decode", "iter_decode", "FbaError", "UnsupportedFeature", "CodingParams", "FapStream",
           "Frame", "FrameRate", "PartParams", "RangeSet", "TimeCode"]
from .encoder import EncodeOptions, encode, plan, write  # noqa: E402
from .summary import describe  # noqa: E402
from .samples import demo_stream  # noqa: E402

__all__ += ["EncodeOptions", "encode", "plan", "write", "describe", "demo_stream"]
