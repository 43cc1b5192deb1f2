"""mpeg4fa: MPEG-4 Face Animation (the FBA object of ISO/IEC 14496-2) in Python.

Packages, one per layer: ``spec`` (the standard's tables, loaded from spec/),
``fba`` (the bitstream codec), ``formats`` (.fap text files), ``cli`` (the
``mpeg4fa`` command). See README.md for the architecture.
"""
__version__ = "0.1.0"
