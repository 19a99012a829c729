#!/usr/bin/env bash
# Fetches the game levels of Recast's demo (dungeon.obj, nav_test.obj, undulating.obj; zlib
# licence, Mikko Mononen) into data/recast/ (or $1). They ship inside the sources of the
# `recastnavigation-sys` crate: `cargo fetch` of a scratch manifest brings them from the
# package registry without building anything. The levels are y up, in metres.
set -euo pipefail
cd "$(dirname "$0")/.."
DEST=${1:-data/recast}
VERSION=1.0.3
if [ -f "$DEST/dungeon.obj" ] && [ -f "$DEST/nav_test.obj" ] && [ -f "$DEST/undulating.obj" ]; then
    echo "already fetched: $DEST"
    exit 0
fi
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
mkdir -p "$WORK/src"
cat > "$WORK/Cargo.toml" <<TOML
[package]
name = "fetch-recast-levels"
version = "0.0.0"
edition = "2021"
publish = false

[dependencies]
recastnavigation-sys = "=$VERSION"
TOML
echo 'fn main() {}' > "$WORK/src/main.rs"
cargo fetch --manifest-path "$WORK/Cargo.toml" >/dev/null 2>&1 || {
    echo "cargo fetch of recastnavigation-sys $VERSION failed: is the crate registry reachable?" >&2
    exit 1
}
SRC=$(find "${CARGO_HOME:-$HOME/.cargo}/registry/src" -maxdepth 2 -type d \
    -name "recastnavigation-sys-$VERSION" | head -n 1)
if [ -z "$SRC" ]; then
    echo "recastnavigation-sys-$VERSION is not in the cargo registry after the fetch" >&2
    exit 1
fi
mkdir -p "$DEST"
cp "$SRC"/recastnavigation/RecastDemo/Bin/Meshes/{dungeon,nav_test,undulating}.obj "$DEST/"
cp "$SRC"/recastnavigation/License.txt "$DEST/LICENSE"
echo "recastnavigation-sys $VERSION" > "$DEST/PACKAGE"
echo "fetched $(ls "$DEST"/*.obj | wc -l) levels of recastnavigation-sys $VERSION into $DEST"
