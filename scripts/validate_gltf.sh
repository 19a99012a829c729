#!/usr/bin/env bash
# Validates GLB/glTF files with the Khronos glTF-Validator (npm `gltf-validator`, installed
# on first use into target/npm/, never committed): `scripts/validate_gltf.sh out/*.glb`.
# Prints each file's errors, warnings and infos; exits 1 if any file has an error.
# `scripts/validate_gltf.sh --install` installs it and does nothing else (CI's first step).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
NPM_DIR=${ENVFIELD_NPM_DIR:-$ROOT/target/npm}
VERSION=2.0.0-dev.3.10
if [ ! -f "$NPM_DIR/node_modules/gltf-validator/package.json" ]; then
    mkdir -p "$NPM_DIR"
    (cd "$NPM_DIR" && npm install --silent --no-audit --no-fund "gltf-validator@$VERSION" >/dev/null) || {
        echo "npm install gltf-validator@$VERSION failed: is the npm registry reachable?" >&2
        exit 1
    }
fi
[ "${1:-}" = "--install" ] && { echo "gltf-validator $VERSION in $NPM_DIR"; exit 0; }
[ "$#" -gt 0 ] || { echo "usage: $0 FILE.glb... | --install" >&2; exit 2; }
VALIDATOR_DIR="$NPM_DIR/node_modules" node "$ROOT/scripts/js/validate_gltf.mjs" "$@"
