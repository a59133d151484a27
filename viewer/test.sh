#!/usr/bin/env bash
# The viewer's browser tests in one command: installs what is missing (setup.sh), builds the page,
# runs tests/*.test.mjs in headless Chromium, and ends with "N passed, N failed".
# HTNGTP_PLAN=path/to/plan.json runs them on another plan (default: fixtures/sample-plan.json).
# HTNGTP_BIN=path/to/htngtp also tests `htngtp view`; by default a built binary under the cargo
# target directory is used when it has the `view` subcommand.
# With that binary and ../shared/robots beside the checkout, tests/real-pr2.test.mjs plans the
# real PR2 (about 20 s; HTNGTP_PR2_PLAN=plan.json uses a plan instead) and checks that the page
# loads its visual meshes from `htngtp view`.
set -euo pipefail
cd "$(dirname "$0")"
./setup.sh
npm run build --silent
if [ -z "${HTNGTP_BIN:-}" ]; then
  target="${CARGO_TARGET_DIR:-../target}"
  for b in "$target/debug/htngtp" "$target/release/htngtp"; do
    if [ -x "$b" ] && "$b" view --help >/dev/null 2>&1; then
      HTNGTP_BIN="$(cd "$(dirname "$b")" && pwd)/htngtp"
      break
    fi
  done
fi
if [ -n "${HTNGTP_BIN:-}" ]; then
  export HTNGTP_BIN
  echo "viewer tests: htngtp view from $HTNGTP_BIN"
else
  echo "viewer tests: no built htngtp with \`view\` found (cargo build -p htngtp, or set HTNGTP_BIN): its tests are skipped"
fi
tap="$(mktemp)"
trap 'rm -f "$tap"' EXIT
status=0
node --test --test-concurrency=1 \
  --test-reporter=spec --test-reporter-destination=stdout \
  --test-reporter=tap --test-reporter-destination="$tap" \
  tests/ || status=$?
passed="$(sed -n 's/^# pass \([0-9]*\)$/\1/p' "$tap")"
failed="$(sed -n 's/^# fail \([0-9]*\)$/\1/p' "$tap")"
if [ -z "$passed" ] || [ -z "$failed" ]; then
  echo "viewer tests: the test runner gave no summary (exit $status)" >&2
  echo "0 passed, 1 failed"
  exit 1
fi
[ "$status" -ne 0 ] && [ "$failed" -eq 0 ] && failed=1
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ] && [ "$status" -eq 0 ]
