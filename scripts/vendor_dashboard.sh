#!/usr/bin/env bash
# Re-fetch the dashboard's third-party files from the npm registry, exactly the pinned versions,
# and check them against the recorded sha256 sums (api/dashboard/static/vendor/SHA256SUMS).
# Usage: scripts/vendor_dashboard.sh [--update]   (--update rewrites SHA256SUMS after a bump)
set -euo pipefail
cd "$(dirname "$0")/.."
UPLOT=1.6.32
THREE=0.187.0
vendor=api/dashboard/static/vendor
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
(cd "$work" && npm pack --silent "uplot@$UPLOT" "three@$THREE" >/dev/null)
tar -xzf "$work/uplot-$UPLOT.tgz" -C "$work" && mv "$work/package" "$work/uplot"
tar -xzf "$work/three-$THREE.tgz" -C "$work" && mv "$work/package" "$work/three"
mkdir -p "$vendor/uplot" "$vendor/three/addons"
cp "$work/uplot/dist/uPlot.iife.min.js" "$work/uplot/dist/uPlot.min.css" "$work/uplot/LICENSE" \
  "$vendor/uplot/"
cp "$work/three/build/three.module.js" "$work/three/build/three.core.js" "$work/three/LICENSE" \
  "$vendor/three/"
cp "$work/three/examples/jsm/controls/OrbitControls.js" "$vendor/three/addons/"
cd "$vendor"
if [[ "${1:-}" == "--update" ]]; then
  find . -type f ! -name SHA256SUMS ! -name README.md | sort | xargs sha256sum >SHA256SUMS
else
  sha256sum --check --quiet SHA256SUMS && echo "vendored files match SHA256SUMS"
fi
