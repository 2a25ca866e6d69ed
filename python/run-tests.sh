#!/usr/bin/env bash
# Builds the Python package and runs its tests, as a user would install it:
#   1. a venv under the cargo target dir (target/py-cablevib-venv) with pinned maturin, pytest, numpy
#      and the dask extra's dask[distributed] and pandas;
#   2. `pip install ./python` (maturin, release build; --no-build-isolation so the pinned
#      maturin builds it) into that venv;
#   3. pytest on python/tests/, which compares the bindings with the `cablevib` binary
#      (CABLEVIB_BIN, default: built here by `cargo build --release --locked`).
# The extension builds into the workspace's target dir (CARGO_TARGET_DIR, default target/)
# so it reuses the compiled dependencies the Rust build left there.
# Extra arguments go to pytest (e.g. `python/run-tests.sh -k analyze`).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
MATURIN_VERSION=1.16.0
PYTEST_VERSION=9.2.0
NUMPY_VERSION=2.4.6
# cablevib.dask's extra (tests/test_dask.py runs a LocalCluster of 2 worker processes).
DASK_VERSION=2026.8.0
PANDAS_VERSION=3.1.1

export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$root/target}"
venv="$CARGO_TARGET_DIR/py-cablevib-venv"
echo "== python: venv $venv ($(python3 --version))"
python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check \
    "maturin==$MATURIN_VERSION" "pytest==$PYTEST_VERSION" "numpy==$NUMPY_VERSION" \
    "dask[distributed]==$DASK_VERSION" "pandas==$PANDAS_VERSION"
# pip runs the maturin of the venv (build backend without isolation).
export PATH="$venv/bin:$PATH"

if [[ -z "${CABLEVIB_BIN:-}" ]]; then
    echo "== python: the cablevib binary the tests compare with"
    cargo build --release --locked --bin cablevib
    export CABLEVIB_BIN="$CARGO_TARGET_DIR/release/cablevib"
fi

echo "== python: pip install ./python (maturin, release)"
start=$SECONDS
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check \
    --no-build-isolation --force-reinstall --no-deps ./python
echo "built and installed in $((SECONDS - start)) s"

echo "== python: pytest"
cd python
exec "$venv/bin/python" -m pytest -p no:cacheprovider tests "$@"
