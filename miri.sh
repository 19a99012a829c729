#!/usr/bin/env bash
# Runs the unit tests of the crates with `unsafe` code under Miri (undefined behaviour,
# out-of-bounds and uninitialised reads): eikonal's heap and marcher, nets' convolution
# kernel. Needs the nightly toolchain with the miri component
# (`rustup component add miri --toolchain nightly`). Under Miri the CPU reports no AVX2 or
# AVX-512, so the kernel's portable path is the one checked; the intrinsics paths are checked
# against the same definition by the ordinary test run.
set -euo pipefail
cd "$(dirname "$0")"
export MIRIFLAGS="${MIRIFLAGS:--Zmiri-strict-provenance}"
echo "== envfield-eikonal: the heap, the marcher (2D and 3D, both orders, speed maps)"
cargo +nightly miri test -p envfield-eikonal --lib
echo "== envfield-nets: the direct convolution kernel"
cargo +nightly miri test -p envfield-nets --lib kernel
