#!/usr/bin/env bash
# Fetches Sweet Home 3D's default furniture catalogue (Debian package `sweethome3d`) into
# data/sweethome3d/ (or $1): the catalogue's properties file and its OBJ models. No Java is
# needed: the package is unpacked with dpkg-deb and the jar with unzip (or python3).
#
# The models are GPL (or CC-BY): never commit them or rooms made from them. data/sweethome3d/
# is ignored by git. Tests and examples that compose rooms from them look here (or at
# $ENVFIELD_SWEETHOME3D).
set -euo pipefail
cd "$(dirname "$0")/.."
DEST=${1:-data/sweethome3d}
if [ -f "$DEST/DefaultFurnitureCatalog.properties" ]; then
    echo "already fetched: $DEST"
    exit 0
fi
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
(cd "$WORK" && apt-get download sweethome3d >/dev/null 2>&1) || {
    echo "apt-get download sweethome3d failed: is a Debian package registry reachable?" >&2
    exit 1
}
dpkg-deb -x "$WORK"/sweethome3d_*.deb "$WORK/deb"
JAR="$WORK/deb/usr/share/sweethome3d/sweethome3d.jar"
mkdir -p "$WORK/jar"
if command -v unzip >/dev/null; then
    unzip -q "$JAR" 'com/eteks/sweethome3d/io/*' -d "$WORK/jar"
else
    python3 -c "import sys, zipfile; z = zipfile.ZipFile(sys.argv[1]); \
[z.extract(n, sys.argv[2]) for n in z.namelist() if n.startswith('com/eteks/sweethome3d/io/')]" \
        "$JAR" "$WORK/jar"
fi
IO="$WORK/jar/com/eteks/sweethome3d/io"
mkdir -p "$DEST/resources"
cp "$IO/DefaultFurnitureCatalog.properties" "$DEST/"
cp "$IO"/resources/*.obj "$DEST/resources/"
cp "$WORK/deb/usr/share/doc/sweethome3d/copyright" "$DEST/COPYRIGHT"
ls "$WORK"/sweethome3d_*.deb | sed 's|.*/||' > "$DEST/PACKAGE"
echo "fetched $(ls "$DEST/resources" | wc -l) models of $(cat "$DEST/PACKAGE") into $DEST"
