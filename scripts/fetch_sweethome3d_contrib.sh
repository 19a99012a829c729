#!/usr/bin/env bash
# Fetches the furniture Sweet Home 3D's contributors modelled (Debian package
# `sweethome3d-furniture`: Blend Swap's CC0 and CC-BY libraries, Kator Legaz's, Scopia's) into
# data/sweethome3d-contrib/ (or $1): each library's PluginFurnitureCatalog.properties and its
# OBJ models, under the paths the properties name. Other modellers than the default
# catalogue's (eTeks), whose models the project was tuned on: the apartments of the held-out
# protocol are furnished from them (docs/rooms.md, "Apartments").
#
# The models are CC-BY or CC0 (see COPYRIGHT); they are fetched, never committed, like the
# default catalogue. data/sweethome3d-contrib/ is ignored by git.
set -euo pipefail
cd "$(dirname "$0")/.."
DEST=${1:-data/sweethome3d-contrib}
LIBRARIES="BlendSwap-CC-0 BlendSwap-CC-BY KatorLegaz Scopia"
if [ -f "$DEST/PACKAGE" ]; then
    echo "already fetched: $DEST"
    exit 0
fi
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
(cd "$WORK" && apt-get download sweethome3d-furniture >/dev/null 2>&1) || {
    echo "apt-get download sweethome3d-furniture failed: is a Debian package registry reachable?" >&2
    exit 1
}
dpkg-deb -x "$WORK"/sweethome3d-furniture_*.deb "$WORK/deb"
mkdir -p "$DEST"
for lib in $LIBRARIES; do
    SH3F="$WORK/deb/usr/share/sweethome3d/furniture/$lib.sh3f"
    mkdir -p "$DEST/$lib"
    if command -v unzip >/dev/null; then
        unzip -q -o "$SH3F" 'PluginFurnitureCatalog.properties' '*.obj' -d "$DEST/$lib"
    else
        python3 -c "import sys, zipfile; z = zipfile.ZipFile(sys.argv[1]); \
[z.extract(n, sys.argv[2]) for n in z.namelist() \
 if n == 'PluginFurnitureCatalog.properties' or n.endswith('.obj')]" "$SH3F" "$DEST/$lib"
    fi
done
cp "$WORK/deb/usr/share/doc/sweethome3d-furniture/copyright" "$DEST/COPYRIGHT"
ls "$WORK"/sweethome3d-furniture_*.deb | sed 's|.*/||' > "$DEST/PACKAGE"
echo "fetched $(find "$DEST" -name '*.obj' | wc -l) models of $(cat "$DEST/PACKAGE") into $DEST"
