"""The standard's numbers as plain JSON-able data, for decoders outside Python (``fba.js``).

The JavaScript decoder must use the very tables the Python codec uses, never a retyped copy, so
``tools/fbajs_spec.py`` writes this (plus the file signatures and the shown-value bounds of the
layers above) next to ``fba.js`` at build time, and a test checks the written file is current.
"""
from __future__ import annotations

from typing import Any

from mpeg4fa.spec import (BAP_GROUPS, BAP_PRED_SCALE, BAP_QUANT_STEP, EXPRESSIONS, FAP_GROUP, FAP_GROUP_SLICES,
                          FAP_PARTNERS, FULL_INTENSITY, HIGH_LEVEL_FIELDS, I_MAX_DEFAULT, N_BAPS, N_FAPS,
                          P_MAX_DEFAULT, QUANT_STEP, VISEMES)
from mpeg4fa.spec.frame_rate import FPS_STEPS, FRAME_RATE_BITS, FREQUENCY_OFFSET_BITS, SECONDS_BITS

SCHEMA = 1
"""Bumped when a key changes meaning, so a reader can refuse tables it does not understand."""


def codec_tables() -> dict[str, Any]:
    """What a bitstream decoder needs: sizes, FAP/BAP groups, quantiser steps, default ranges,
    the FAP 1/2 fields and the frame-rate field widths."""
    return {
        "n_faps": int(N_FAPS),
        "n_baps": int(N_BAPS),
        "fap_group_slices": [[int(a), int(b)] for a, b in FAP_GROUP_SLICES],
        "fap_quant_step": [int(x) for x in QUANT_STEP],
        "fap_i_max_default": [int(x) for x in I_MAX_DEFAULT],
        "fap_p_max_default": [int(x) for x in P_MAX_DEFAULT],
        "bap_groups": [[int(i) for i in g] for g in BAP_GROUPS],
        "bap_quant_step": [int(x) for x in BAP_QUANT_STEP],
        "bap_pred_scale": [int(x) for x in BAP_PRED_SCALE],
        "high_level_fields": [{"fap": f.fap, "field": f.field, "i_min": f.i_min, "i_max": f.i_max,
                               "p_min": f.p_min, "p_max": f.p_max, "quantised": f.quantised}
                              for f in HIGH_LEVEL_FIELDS],
        "full_intensity": int(FULL_INTENSITY),
        "frame_rate_bits": int(FRAME_RATE_BITS),
        "seconds_bits": int(SECONDS_BITS),
        "frequency_offset_bits": int(FREQUENCY_OFFSET_BITS),
        "fps_steps": int(FPS_STEPS),
    }


def shown_tables() -> dict[str, Any]:
    """What turns sent FAPs into shown ones: groups, counterparts, and the viseme and expression
    profiles (68 FAPU values at full strength, in FAP 1 / FAP 2 select-code order)."""
    from mpeg4fa.spec.profiles import _LIMITS, EXPRESSION_PROFILES, VISEME_PROFILES

    return {
        "fap_group": [int(x) for x in FAP_GROUP],
        "fap_partners": [[int(a), int(b)] for a, b in FAP_PARTNERS],
        "visemes": [v.name for v in VISEMES],
        "expressions": [e.name for e in EXPRESSIONS],
        "viseme_profiles": [[int(x) for x in VISEME_PROFILES["mpeg4"][v.name]] for v in VISEMES],
        "expression_profiles": [[int(x) for x in EXPRESSION_PROFILES[e.name]] for e in EXPRESSIONS],
        # per FAP 1 / FAP 2 row field: [syntax name, lowest, highest, kind], the rule expand_high_level checks
        "high_level_limits": {str(fap): [list(field) for field in fields] for fap, fields in _LIMITS.items()},
    }


def tables() -> dict[str, Any]:
    """Everything of ``spec/`` a decoder outside Python reads (:func:`codec_tables` + :func:`shown_tables`)."""
    return {"schema": SCHEMA, **codec_tables(), **shown_tables()}
