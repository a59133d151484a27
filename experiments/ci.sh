#!/usr/bin/env bash
# The Lab experiments' CI test (run by .ci/run): a virtual environment under target/labenv (or
# $HTNGTP_LABENV) with experiments/requirements.txt installed from PyPI when missing, then
# experiments/ci_test.py on the htngtp binary $HTNGTP_BIN (default target/debug/htngtp, built
# when missing): a tiny HDDL suite and a few library and GTP runs through Lab's local
# environment, the parsed attributes and the reports checked.
set -euo pipefail
cd "$(dirname "$0")/.."
venv="${HTNGTP_LABENV:-$PWD/target/labenv}"
python="${PYTHON:-python3}"
binary="${HTNGTP_BIN:-$PWD/target/debug/htngtp}"
if [ ! -x "$venv/bin/python" ]; then
    "$python" -m venv "$venv"
fi
if ! "$venv/bin/python" -c "import lab, matplotlib" 2>/dev/null; then
    "$venv/bin/python" -m pip install --quiet -r experiments/requirements.txt
fi
if [ ! -x "$binary" ]; then
    if [ -n "${HTNGTP_BIN:-}" ]; then
        echo "error: HTNGTP_BIN=$binary is not an executable file" >&2
        exit 2
    fi
    cargo build -p htngtp
fi
"$venv/bin/python" experiments/ci_test.py --binary "$binary" "$@"
