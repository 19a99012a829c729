#!/usr/bin/env bash
# Fetches the glTF 2.0 test models of Debian's `assimp-testmodels` (the Open Asset Import
# Library's test set: Khronos sample models, the glTF Asset Generator's primitive modes, and
# files built to break importers: out-of-range indices, missing buffers, recursive nodes,
# wrong JSON types, Draco) into data/assimp-gltf/ (or $1), keeping the package's folders.
# The glTF reader's tests read every one (crates/scene/tests/gltf.rs): each is read or refused
# with a clear error, none panics.
#
# Their licences vary by model (see COPYRIGHT); they are fetched, never committed.
# data/assimp-gltf/ is ignored by git.
set -euo pipefail
cd "$(dirname "$0")/.."
DEST=${1:-data/assimp-gltf}
if [ -f "$DEST/PACKAGE" ]; then
    echo "already fetched: $DEST"
    exit 0
fi
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
(cd "$WORK" && apt-get download assimp-testmodels >/dev/null 2>&1) || {
    echo "apt-get download assimp-testmodels failed: is a Debian package registry reachable?" >&2
    exit 1
}
dpkg-deb -x "$WORK"/assimp-testmodels_*.deb "$WORK/deb"
mkdir -p "$DEST"
cp -r "$WORK/deb/usr/share/assimp/models/glTF2/." "$DEST/"
cp "$WORK/deb/usr/share/doc/assimp-testmodels/copyright" "$DEST/COPYRIGHT"
ls "$WORK"/assimp-testmodels_*.deb | sed 's|.*/||' > "$DEST/PACKAGE"
echo "fetched $(find "$DEST" -name '*.gltf' -o -name '*.glb' | wc -l) glTF files of $(cat "$DEST/PACKAGE") into $DEST"
