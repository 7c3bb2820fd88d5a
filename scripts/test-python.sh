#!/usr/bin/env bash
# The Python package's tests: makes target/py-venv if it is missing,
# builds and installs ./python into it with maturin (through pip, with the
# test extras), then runs pytest on python/tests. The build uses the dev
# profile (opt-level 2, shared target/) unless CHISEL_PY_PROFILE says
# otherwise (`release` is what a plain `pip install ./python` builds).
# The CLI-equality tests run target/debug/chisel (or CHISEL_BIN).
set -euo pipefail
cd "$(dirname "$0")/.."
venv="${CHISEL_PY_VENV:-target/py-venv}"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet --upgrade pip
MATURIN_PEP517_ARGS="--profile ${CHISEL_PY_PROFILE:-dev}" \
    "$venv/bin/python" -m pip install --quiet "./python[test]"
# The stubs and annotations agree with the calls the package makes.
"$venv/bin/python" -m mypy --ignore-missing-imports --no-incremental python/chisel
# From the repository root, so that `import chisel` finds the installed
# package and not the source folder python/chisel.
"$venv/bin/python" -m pytest -q -p no:cacheprovider python/tests "$@"
