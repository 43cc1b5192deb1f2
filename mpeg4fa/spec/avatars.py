"""The viseme and blend-shape sets of today's avatar systems, and our maps to and from them.

Loaded once from ``spec/`` (see its README, section "Avatar systems"):

* ``arkit_blendshapes.csv``: the 52 ARKit face blend shapes, in the order Azure's blend-shape
  frames list them (:data:`ARKIT_BLENDSHAPES`);
* ``oculus_visemes.csv``: the 15 Oculus/OVR lip-sync visemes (index 0..14), with the MPEG-4
  viseme each one is (the OVR set is the MPEG-4 set renamed, so this map is one-to-one);
* ``azure_visemes.csv``: Azure Speech's 22 viseme IDs with their IPA and the MPEG-4 viseme an
  incoming ID becomes (ours; a diphthong's ID its nucleus, then its offglide);
* ``polly_visemes.csv``: Amazon Polly's en-US viseme alphabet with its IPA and the MPEG-4 viseme
  an incoming speech mark becomes (ours);
* ``viseme_targets.csv``: for every viseme of our two sets (``mpeg4``, ``zh``), the OVR name,
  Azure ID and Polly viseme it goes out as (ours).

A broken data file is a bug in the package (``ValueError`` naming the file and line); a name or
ID from a user's file that the tables do not know is a :class:`~mpeg4fa.spec.errors.SpecError`.
"""
from __future__ import annotations

from dataclasses import dataclass

from mpeg4fa.spec import VISEMES
from mpeg4fa.spec._load import check, read_table, split_list
from mpeg4fa.spec.errors import SpecError
from mpeg4fa.spec.profiles import VISEME_PROFILES

__all__ = [
    "ARKIT_BLENDSHAPES", "OculusViseme", "OCULUS_VISEMES", "AzureViseme", "AZURE_VISEMES", "PollyViseme",
    "POLLY_VISEMES", "VisemeTarget", "VISEME_TARGETS", "viseme_target", "from_azure", "from_polly", "from_oculus",
]

_MPEG4_NAMES = tuple(v.name for v in VISEMES)


def _arkit() -> tuple[str, ...]:
    rows = read_table("arkit_blendshapes.csv", "order,name,region")
    check([r["order"] for r in rows] == [str(k) for k in range(1, len(rows) + 1)],
          "arkit_blendshapes.csv: order must count 1..n")
    names = tuple(r["name"] for r in rows)
    check(len(set(names)) == len(names), "arkit_blendshapes.csv: a blend shape is listed twice")
    return names


ARKIT_BLENDSHAPES = _arkit()
"""The 52 ARKit face blend shape names (``jawOpen``, ``mouthSmileLeft``...), in Azure's frame order."""


@dataclass(frozen=True)
class OculusViseme:
    index: int
    name: str
    phonemes: str
    examples: str
    mpeg4: str
    """The MPEG-4 viseme (``visemes.csv`` name) this OVR viseme is."""


@dataclass(frozen=True)
class AzureViseme:
    id: int
    ipa: tuple[str, ...]
    """IPA of the en-US phonemes Azure shows with this ID (``silence`` for 0)."""
    mpeg4: str
    """The MPEG-4 viseme an incoming event with this ID becomes (a diphthong's nucleus)."""
    offglide: str | None = None
    """A diphthong's second viseme (9 aʊ, 10 ɔɪ, 11 aɪ), shown late in the event's time; None for the rest."""


@dataclass(frozen=True)
class PollyViseme:
    name: str
    ipa: tuple[str, ...]
    mpeg4: str


@dataclass(frozen=True)
class VisemeTarget:
    """How one of our visemes goes out: OVR viseme name, Azure viseme ID, Polly viseme."""

    oculus: str
    azure: int
    polly: str


def _mpeg4(name: str, where: str) -> str:
    check(name in _MPEG4_NAMES, f"{where}: {name!r} is no viseme of visemes.csv")
    return name


def _oculus() -> tuple[OculusViseme, ...]:
    rows = read_table("oculus_visemes.csv", "index,name,phonemes,examples,mpeg4")
    out = tuple(OculusViseme(int(r["index"]), r["name"], r["phonemes"], r["examples"],
                             _mpeg4(r["mpeg4"], f"oculus_visemes.csv line {line}"))
                for line, r in enumerate(rows, start=2))
    check([v.index for v in out] == list(range(len(out))), "oculus_visemes.csv: index must count 0..n-1")
    check(sorted(v.mpeg4 for v in out) == sorted(_MPEG4_NAMES),
          "oculus_visemes.csv: each MPEG-4 viseme must be one OVR viseme")
    return out


def _azure() -> tuple[AzureViseme, ...]:
    rows = read_table("azure_visemes.csv", "id,ipa,mpeg4")
    out = []
    for line, r in enumerate(rows, start=2):
        where = f"azure_visemes.csv line {line}"
        shown = split_list(r["mpeg4"])
        check(len(shown) in (1, 2), f"{where}: one viseme, or a diphthong's two")
        out.append(AzureViseme(int(r["id"]), split_list(r["ipa"]), _mpeg4(shown[0], where),
                               _mpeg4(shown[1], where) if len(shown) == 2 else None))
    out = tuple(out)
    check([v.id for v in out] == list(range(len(out))), "azure_visemes.csv: id must count 0..n-1")
    return out


def _polly() -> tuple[PollyViseme, ...]:
    rows = read_table("polly_visemes.csv", "viseme,ipa,mpeg4")
    out = tuple(PollyViseme(r["viseme"], split_list(r["ipa"]), _mpeg4(r["mpeg4"], f"polly_visemes.csv line {line}"))
                for line, r in enumerate(rows, start=2))
    names = [v.name for v in out]
    check(len(set(names)) == len(names), "polly_visemes.csv: a viseme is listed twice")
    return out


OCULUS_VISEMES = _oculus()
"""The 15 OVR visemes ``sil, PP, FF, TH, DD, kk, CH, SS, nn, RR, aa, E, ih, oh, ou`` (index order)."""
AZURE_VISEMES = _azure()
"""Azure Speech's viseme IDs 0..21 (``AZURE_VISEMES[k].id == k``)."""
POLLY_VISEMES = _polly()
"""Polly's en-US viseme alphabet: ``sil p t S T f k i r s u @ a e E o O``."""

_OCULUS_BY_NAME = {v.name: v for v in OCULUS_VISEMES}
_POLLY_BY_NAME = {v.name: v for v in POLLY_VISEMES}


def _targets() -> dict[tuple[str, str], VisemeTarget]:
    out: dict[tuple[str, str], VisemeTarget] = {}
    for line, r in enumerate(read_table("viseme_targets.csv", "set,viseme,oculus,azure,polly,note"), start=2):
        where = f"viseme_targets.csv line {line}"
        key = (r["set"], r["viseme"])
        check(r["set"] in VISEME_PROFILES and r["viseme"] in VISEME_PROFILES[r["set"]],
              f"{where}: {key} is no viseme of a set in viseme_faps.csv")
        check(key not in out, f"{where}: {key} is listed twice")
        check(r["oculus"] in _OCULUS_BY_NAME, f"{where}: {r['oculus']!r} is no OVR viseme")
        check(r["azure"].isdigit() and int(r["azure"]) < len(AZURE_VISEMES), f"{where}: {r['azure']!r} is no Azure ID")
        check(r["polly"] in _POLLY_BY_NAME, f"{where}: {r['polly']!r} is no Polly viseme")
        out[key] = VisemeTarget(r["oculus"], int(r["azure"]), r["polly"])
    for set_name, names in VISEME_PROFILES.items():
        missing = [n for n in names if (set_name, n) not in out]
        check(not missing, f"viseme_targets.csv: no row for {set_name} visemes {missing}")
    return out


VISEME_TARGETS = _targets()
"""``(set, viseme)`` -> :class:`VisemeTarget`, for every viseme of every set in ``viseme_faps.csv``."""


def viseme_target(viseme: str, set: str = "mpeg4") -> VisemeTarget:
    """The OVR, Azure and Polly visemes one of ours goes out as."""
    try:
        return VISEME_TARGETS[(set, viseme)]
    except KeyError:
        raise SpecError(f"{set} viseme {viseme!r} is not in viseme_targets.csv",
                        hint=f"one of {', '.join(n for s, n in VISEME_TARGETS if s == set)}") from None


def from_azure(viseme_id: int) -> str:
    """The MPEG-4 viseme an Azure viseme ID becomes."""
    if isinstance(viseme_id, bool) or not isinstance(viseme_id, int) or not 0 <= viseme_id < len(AZURE_VISEMES):
        raise SpecError(f"Azure viseme ID {viseme_id!r} is not one of 0..{len(AZURE_VISEMES) - 1}",
                        hint="Azure Speech sends VisemeId 0..21")
    return AZURE_VISEMES[viseme_id].mpeg4


def from_polly(value: str) -> str:
    """The MPEG-4 viseme a Polly viseme speech mark's ``value`` becomes."""
    try:
        return _POLLY_BY_NAME[value].mpeg4
    except (KeyError, TypeError):
        raise SpecError(f"Polly viseme {value!r} is not in polly_visemes.csv",
                        hint=f"Polly's en-US visemes: {' '.join(_POLLY_BY_NAME)}") from None


def from_oculus(name: str) -> str:
    """The MPEG-4 viseme an OVR viseme name is."""
    try:
        return _OCULUS_BY_NAME[name].mpeg4
    except (KeyError, TypeError):
        raise SpecError(f"OVR viseme {name!r} is not in oculus_visemes.csv",
                        hint=f"one of {', '.join(_OCULUS_BY_NAME)}") from None
