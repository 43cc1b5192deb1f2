"""The FBA bitstream codec (ISO/IEC 14496-2 fba_object): decode and encode FAP/BAP streams.

Layers, bottom up: ``bits`` (bit reader/writer, start codes) -> ``arith`` (adaptive
arithmetic coder) -> ``syntax`` and ``params`` (headers, ranges, quantisation,
prediction) -> ``decoder`` / ``encoder`` (planes and frames) -> ``stream`` (the
data model; ``stacking`` builds one in bounded memory); ``limits`` says what a stream
may ask for (frame rates an intra header carries, at most 24 h of frames).
``spec/SYNTAX.md`` describes the bitstream as implemented.
"""
from .decoding import decode, iter_decode
from .encoder import EncodeOptions, encode, plan, write
from .errors import FbaError, UnsupportedFeature
from .samples import demo_stream
from .stream import CodingParams, FapStream, Frame, FrameRate, PartParams, RangeSet, TimeCode
from .summary import describe

__all__ = ["decode", "iter_decode", "encode", "EncodeOptions", "plan", "write", "describe", "demo_stream",
           "FbaError", "UnsupportedFeature", "CodingParams", "FapStream", "Frame", "FrameRate", "PartParams",
           "RangeSet", "TimeCode"]
