#!/usr/bin/env bash
# The viewer's browser tests in one command: installs what is missing (setup.sh), builds the page,
# runs tests/*.test.mjs in headless Chromium, and ends with "N passed, N failed".
# HTNGTP_PLAN=path/to/plan.json runs them on another plan (default: fixtures/sample-plan.json).
set -euo pipefail
cd "$(dirname "$0")"
./setup.sh
npm run build --silent
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
