#!/usr/bin/env bash
# The Python package's tests, as a user gets it: build the wheel (maturin, release), install
# it with pip into a fresh virtual environment (no compiler involved), and run scikit-fmm's
# own doctests against envfield.fmm (fetched from the Python registry by the test) and
# envfield's own Python tests.
#
#   bash python/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."
VENV="$PWD/target/python-test-venv"
BUILD="$PWD/target/python-build-venv"
if [ ! -x "$BUILD/bin/maturin" ]; then
    python3 -m venv "$BUILD"
    "$BUILD/bin/pip" install -q "maturin>=1.9,<2"
fi
rm -rf target/wheels/envfield-*.whl
"$BUILD/bin/maturin" build --release -m python/Cargo.toml -o target/wheels
rm -rf "$VENV"
python3 -m venv "$VENV"
# A binary wheel: nothing is compiled (CC and CXX point at false, and only wheels are taken).
CC=/bin/false CXX=/bin/false "$VENV/bin/pip" install -q --only-binary :all: target/wheels/envfield-*.whl
cd target   # away from python/envfield, so the installed package is the one imported
"$VENV/bin/python" -c "import envfield, sys; print('envfield', envfield.__version__, 'from', envfield.__file__)"
"$VENV/bin/python" -c "import doctest, sys, envfield.fmm as f; r = doctest.testmod(f); print('envfield.fmm docstrings:', r); sys.exit(r.failed > 0)"
"$VENV/bin/python" ../python/tests/skfmm_suite.py
"$VENV/bin/python" -m unittest discover -s ../python/tests
