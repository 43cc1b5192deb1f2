#!/usr/bin/env python
"""Write ``spec/english_ipa.csv``: the IPA name of every phoneme mnemonic an English espeak-ng voice can emit.

A script run when the espeak-ng wheel changes, not a test::

    .venv/bin/python tools/english_ipa.py [--check]

Why: the English route reads espeak's mnemonics (``spec/english_visemes.csv``); a mnemonic that table
lacks (``l#`` in "Bokhl", ``O``) reaches a viseme through its IPA features instead
(:mod:`mpeg4fa.speech.visemes`), and this table says which IPA it is. It must be complete, so it is not
gathered from sample words but from the phoneme tables themselves:

1. ``espeak-ng-data/phontab`` lists each phoneme table (``base``, ``base1``, ``en``, ``en-us``...) and
   the phonemes it defines; a table includes the one it is built on (``en-us`` <- ``en`` <- ``base1``
   <- ``base``), and a voice uses the table its voice file names (``phonemes en-sc``). The phonemes an
   English voice can emit are those of its table and of every table under it;
2. each of those mnemonics is spoken alone as phoneme input (``[[l#]]``, espeak's ``espeakPHONEMES``
   flag), once with mnemonic events and once with IPA events, and the two runs' sounding phonemes are
   paired one for one: that is the IPA espeak itself gives the phoneme. Pauses, stress marks and
   espeak's virtual phonemes emit no event and are left out.

A mnemonic whose IPA differs between English tables (``0`` is ``ɒ`` in ``en``, ``ɑː`` in ``en-us``) keeps
the IPA of the first table in ``TABLES`` order; such conflicts are printed for the mnemonics
``spec/english_visemes.csv`` lacks (elsewhere the IPA is never read). ``--check`` writes nothing and
exits 1 when the file is out of date.
"""
from __future__ import annotations

import argparse
import csv
import ctypes
import io
import struct
import sys
from pathlib import Path

import espeakng_loader

from mpeg4fa.speech.tts import espeak
from mpeg4fa.speech.visemes import english_table

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "spec" / "english_ipa.csv"
TABLES = ("en", "en-us", "en-rp", "en-n", "en-sc", "en-wi", "en-wm", "en-us-nyc")
"""The English phoneme tables, the first one's IPA winning on a conflict (``en``: en-gb's table)."""
ESPEAK_PHONEMES = 0x100
"""espeak_Synth flag: read ``[[...]]`` as phoneme mnemonics."""
TAB_NAME = 32
"""Bytes of a table name in phontab."""
PHONEME_TAB = struct.Struct("<IIHBBBBBB")
"""One phoneme in phontab: mnemonic (4 bytes, first character lowest), flags, program, code, type, ..."""
SILENT_TYPES = {0, 1}
"""phontab types that never sound: pause, stress."""


def phoneme_tables(data: Path) -> tuple[dict[str, tuple[int, list[tuple[int, str, int]]]], list[str]]:
    """phontab read: table name -> (index of the table it includes, or -1; [(code, mnemonic, type)]), and
    the table names in file order (what an index refers to)."""
    raw = (data / "phontab").read_bytes()
    count, at = raw[0], 4
    out: dict[str, tuple[int, list[tuple[int, str, int]]]] = {}
    names: list[str] = []
    for _ in range(count):
        n, includes = raw[at], raw[at + 1]
        name = raw[at + 4:at + 4 + TAB_NAME].split(b"\0", 1)[0].decode("ascii")
        at += 4 + TAB_NAME
        phonemes = []
        for _ in range(n):
            mnemonic, _flags, _program, code, kind, *_ = PHONEME_TAB.unpack_from(raw, at)
            at += PHONEME_TAB.size
            text = struct.pack("<I", mnemonic).split(b"\0", 1)[0].decode("latin-1")
            if text:
                phonemes.append((code, text, kind))
        names.append(name)
        out[name] = (includes - 1, phonemes)
    return out, names


def table_phonemes(tables, names: list[str], table: str) -> dict[int, tuple[str, int]]:
    """code -> (mnemonic, type) of every phoneme a voice on ``table`` can use (included tables first)."""
    includes, phonemes = tables[table]
    found = table_phonemes(tables, names, names[includes]) if includes >= 0 else {}
    found.update({code: (text, kind) for code, text, kind in phonemes})
    return found


def voice_of_table(data: Path) -> dict[str, str]:
    """Phoneme table -> an installed English voice that uses it (from the voice files' ``phonemes`` lines)."""
    out: dict[str, str] = {}
    for v in espeak.voices():
        if not v.language.startswith("en") or not v.identifier:
            continue
        table = v.language.split("-")[0]
        for line in (data / "lang" / v.identifier).read_text("utf-8", "replace").splitlines():
            if line.split()[:1] == ["phonemes"]:
                table = line.split()[1]
        out.setdefault(table, v.identifier)
    return out


def spoken(text: str, voice: str, ipa: bool) -> list[str]:
    """The phoneme events (names, stress stripped, pauses left out) of ``text`` read as phoneme input."""
    with espeak._lock:
        lib = espeak._load()
        if lib.espeak_SetVoiceByName(voice.encode()) != espeak.EE_OK:
            raise SystemExit(f"cannot set voice {voice}")
        col = espeak._collector = espeak._Collector()
        lib.espeak_ng_SetPhonemeEvents(1, 1 if ipa else 0)
        try:
            data = text.encode() + b"\0"
            buf = ctypes.create_string_buffer(data, len(data))
            lib.espeak_Synth(buf, len(data), 0, espeak.POS_CHARACTER, 0, espeak.espeakCHARS_UTF8 | ESPEAK_PHONEMES,
                             None, None)
            lib.espeak_Synchronize()
        finally:
            espeak._collector = None
            lib.espeak_ng_SetPhonemeEvents(1, 0)
    names = [e.name.lstrip(espeak.STRESS_MARKS) or e.name for e in col.events if e.type == espeak.EV_PHONEME]
    return names


def build() -> tuple[str, list[str]]:
    """The CSV text and the notes (conflicts, mnemonics that spoke as something else)."""
    data = Path(espeakng_loader.get_data_path())
    tables, names = phoneme_tables(data)
    voices = voice_of_table(data)
    rows: dict[str, tuple[str, str]] = {}
    notes: list[str] = []
    for table in TABLES:
        if table not in tables or table not in voices:
            notes.append(f"table {table}: not installed or no voice uses it")
            continue
        for code, (text, kind) in sorted(table_phonemes(tables, names, table).items()):
            if kind in SILENT_TYPES or text.startswith("_"):
                continue
            source = f"[[{text}]]"
            mnemonics, ipas = spoken(source, voices[table], False), spoken(source, voices[table], True)
            pairs = [(m, i) for m, i in zip(mnemonics, ipas) if not m.startswith("_")]
            if len(mnemonics) != len(ipas):
                notes.append(f"{table} {text!r}: the two runs gave {mnemonics} and {ipas}; left out")
                continue
            for m, i in pairs:
                if m in rows and rows[m][0] != i:
                    if m not in english_table():  # where the English table decides, the IPA is never read
                        notes.append(f"{m!r}: {rows[m][0]!r} in {rows[m][1]}, {i!r} in {table} (kept {rows[m][0]!r})")
                    continue
                rows.setdefault(m, (i, table))
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["phoneme", "ipa", "table"])
    for mnemonic in sorted(rows):
        writer.writerow([mnemonic, *rows[mnemonic]])
    return out.getvalue(), notes


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="write nothing; exit 1 if the file is out of date")
    args = parser.parse_args(argv)
    text, notes = build()
    for note in dict.fromkeys(notes):
        print(note, file=sys.stderr)
    rows = text.count("\n") - 1
    if args.check:
        same = OUT.exists() and OUT.read_text("utf-8") == text
        print(f"{OUT.relative_to(ROOT)}: {'up to date' if same else 'out of date'} ({rows} mnemonics)")
        return 0 if same else 1
    OUT.write_text(text, "utf-8")
    print(f"wrote {OUT.relative_to(ROOT)} ({rows} mnemonics)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
