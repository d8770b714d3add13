#!/usr/bin/env bash
# Refresh the locks that CI, the README's test command and the Dockerfile install through:
#   requirements/dev.txt      runtime + service and dev extras + build backend (CI, the test command)
#   requirements/runtime.txt  runtime + service extra + build backend, the same versions (the
#                             Docker image: everything `softevo serve` and `worker` need)
# Both are resolved by uv for Python 3.11 on every platform (--universal), with sha256 hashes.
# Usage: scripts/lock.sh [--upgrade]   (without it, versions already locked are kept if they
# still satisfy pyproject.toml; with it, every package moves to its newest allowed release).
# Needs uv (`pip install uv`). Afterwards run the tests: tests/test_lock.py checks the agreement.
set -euo pipefail
cd "$(dirname "$0")/.."
command -v uv >/dev/null 2>&1 || { echo "scripts/lock.sh: uv is not installed (pip install uv)" >&2; exit 1; }
common=(--custom-compile-command scripts/lock.sh --generate-hashes --universal --python-version 3.11 --quiet "$@")
uv pip compile pyproject.toml requirements/build.in --extra service --extra dev "${common[@]}" \
  -o requirements/dev.txt
uv pip compile pyproject.toml requirements/build.in --extra service -c requirements/dev.txt "${common[@]}" \
  -o requirements/runtime.txt
echo "locked: $(grep -c '^[a-z]' requirements/dev.txt) packages (dev), $(grep -c '^[a-z]' requirements/runtime.txt) (runtime)"
