#!/usr/bin/env bash
# Fetches three.js (MIT; npm package `three`, pinned) into data/three/ (or $1): the module
# build and the three add-ons the viewer page uses (GLTFLoader, its BufferGeometryUtils, and
# OrbitControls), with its licence. `--html` pages embed them, so a page opens with no
# network; the page's test opens one in headless Chromium (crates/examples/tests/viewer.rs).
# Fetched, never committed; data/three/ is ignored by git.
set -euo pipefail
cd "$(dirname "$0")/.."
DEST=${1:-data/three}
VERSION=0.171.0
if [ -f "$DEST/VERSION" ] && [ "$(cat "$DEST/VERSION")" = "$VERSION" ]; then
    echo "already fetched: $DEST"
    exit 0
fi
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
(cd "$WORK" && npm pack --silent "three@$VERSION" >/dev/null) || {
    echo "npm pack three@$VERSION failed: is the npm registry reachable?" >&2
    exit 1
}
tar xzf "$WORK/three-$VERSION.tgz" -C "$WORK"
P="$WORK/package"
mkdir -p "$DEST"
cp "$P/build/three.module.min.js" "$P/build/three.core.min.js" "$P/LICENSE" "$DEST/"
cp "$P/examples/jsm/loaders/GLTFLoader.js" "$P/examples/jsm/utils/BufferGeometryUtils.js" \
    "$P/examples/jsm/controls/OrbitControls.js" "$DEST/"
echo "$VERSION" > "$DEST/VERSION"
echo "fetched three.js $VERSION into $DEST"
