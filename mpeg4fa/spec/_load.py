"""Locating and parsing the CSV tables of the top-level ``spec/`` folder.

An installed package ships that folder as the data package
``mpeg4fa.spec_data``; a source checkout reads it in place.
"""
from __future__ import annotations

import csv
from importlib import resources
from importlib.resources.abc import Traversable
from pathlib import Path


def data_dir() -> Traversable:
    """Folder holding the tables: the installed data package, else the checkout's ``spec/``."""
    try:
        return resources.files("mpeg4fa.spec_data")
    except ModuleNotFoundError:
        return Path(__file__).resolve().parents[2] / "spec"


def read_table(name: str, columns: str) -> list[dict[str, str]]:
    """Rows of ``name`` as dicts; fail if its header is not exactly ``columns``.

    Checking the header catches a column renamed or moved in the data file
    instead of silently reading the wrong one.
    """
    with (data_dir() / name).open("r", encoding="utf-8", newline="") as f:
        reader = csv.DictReader(f)
        wanted = columns.split(",")
        if reader.fieldnames != wanted:
            raise ValueError(f"{name}: header {reader.fieldnames} != {wanted}")
        return list(reader)


def opt_str(text: str) -> str | None:
    """Empty cell -> None."""
    return text or None


def opt_int(text: str) -> int | None:
    """Integer cell, or None when empty."""
    return int(text) if text else None


def opt_float(text: str) -> float | None:
    """Number cell, or None when empty."""
    return float(text) if text else None


def split_list(text: str) -> tuple[str, ...]:
    """Cell holding a ``;``-separated list (empty cell -> empty tuple)."""
    return tuple(item.strip() for item in text.split(";") if item.strip())


def check(condition: bool, message: str) -> None:
    """Raise when a data file breaks an invariant the codec relies on."""
    if not condition:
        raise ValueError(f"spec tables: {message}")
