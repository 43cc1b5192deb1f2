#!/usr/bin/env bash
# Vendor three.js from the npm registry into the editor's static files (no CDN at run time).
#   tools/vendor_three.sh [VERSION]     (default: the version pinned below)
# Writes mpeg4fa/web/static/vendor/three/: the ES module build (three.module.js + three.core.js),
# the add-ons the pages import (ADDONS below, with the utils GLTFLoader needs), three.js's MIT licence, and VENDORED.md with the version and checksums.
set -euo pipefail
cd "$(dirname "$0")/.."
VERSION=${1:-0.187.0}
DEST=mpeg4fa/web/static/vendor/three
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
(cd "$WORK" && npm pack --silent "three@$VERSION" >/dev/null && tar xzf "three-$VERSION.tgz")
PKG="$WORK/package"
ADDONS="controls/OrbitControls.js controls/TransformControls.js loaders/GLTFLoader.js utils/BufferGeometryUtils.js utils/SkeletonUtils.js"
cp "$PKG/build/three.module.js" "$PKG/build/three.core.js" "$PKG/LICENSE" "$DEST/"
for addon in $ADDONS; do
    mkdir -p "$DEST/addons/$(dirname "$addon")"
    cp "$PKG/examples/jsm/$addon" "$DEST/addons/$addon"
done
{
    echo "# three.js $VERSION, vendored"
    echo
    echo "From the npm registry (\`npm pack three@$VERSION\`) by \`tools/vendor_three.sh\`; MIT licence in LICENSE."
    echo "The page imports \`three\` and \`three/addons/\` through an import map pointing here."
    echo
    echo '```'
    (cd "$DEST" && sha256sum three.module.js three.core.js $(for a in $ADDONS; do echo "addons/$a"; done) LICENSE)
    echo '```'
} > "$DEST/VENDORED.md"
echo "vendored three.js $VERSION into $DEST"
