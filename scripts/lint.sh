#!/usr/bin/env bash
# The checks CI runs before the tests: ruff (lint and format), mypy and import-linter's
# contracts (pyproject.toml). The contracts are checked on the tree as installed, `softevo.core` and all
# (the repository keeps core/, api/, worker/ and migrations/ at its top; pyproject maps them
# under softevo), so the folders are staged that way first: grimp reads folders, not mappings.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
python -m ruff check .
python -m ruff format --check .
stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
cp -r softevo "$stage/softevo"
for folder in core api worker migrations; do
  cp -r "$folder" "$stage/softevo/$folder"
done
# mypy on the tree as installed ([tool.mypy] in pyproject.toml), its paths printed as the
# repository's; then lint-imports, called through the interpreter (its console script may not
# be on PATH yet)
(cd "$stage" && python -m mypy --config-file "$root/pyproject.toml" --cache-dir "$root/.mypy_cache" -p softevo) |
  sed -E 's#^softevo/(core|api|worker|migrations)/#\1/#'
(cd "$stage" && python -c 'import sys; from importlinter.cli import lint_imports_command as c
sys.argv[0] = "lint-imports"; c()' --config "$root/pyproject.toml" --no-cache)
