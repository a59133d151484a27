#!/usr/bin/env bash
# Builds the Python package into a virtual environment under target/ and runs its pytest tests.
# The environment (target/pyenv, or $HTNGTP_PYENV) is created on first use, with maturin, numpy
# and pytest installed from PyPI when missing; `maturin develop` builds the native module with
# the dev profile into the shared target/ folder, so it reuses `cargo test`'s build.
set -euo pipefail
cd "$(dirname "$0")/.."
venv="${HTNGTP_PYENV:-$PWD/target/pyenv}"
python="${PYTHON:-python3}"
if [ ! -x "$venv/bin/python" ]; then
    "$python" -m venv "$venv"
fi
if ! "$venv/bin/python" -c "import maturin, numpy, pytest" 2>/dev/null; then
    "$venv/bin/python" -m pip install --quiet "maturin>=1.9.4,<2" numpy pytest
fi
(cd python && VIRTUAL_ENV="$venv" PATH="$venv/bin:$PATH" maturin develop --quiet)
"$venv/bin/python" -m pytest -q python/tests "$@"
