#!/usr/bin/env bash
# Re-fetch the dashboard's (and /docs') third-party files from the npm registry, exactly the pinned versions,
# and check them against the recorded sha256 sums (api/dashboard/static/vendor/SHA256SUMS).
# Usage: scripts/vendor_dashboard.sh [--update]   (--update rewrites SHA256SUMS after a bump)
set -euo pipefail
cd "$(dirname "$0")/.."
UPLOT=1.6.32
THREE=0.187.0
SWAGGER=5.35.0 # swagger-ui-dist, for the offline /docs page
vendor=api/dashboard/static/vendor
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
(cd "$work" && npm pack --silent "uplot@$UPLOT" "three@$THREE" "swagger-ui-dist@$SWAGGER" >/dev/null)
tar -xzf "$work/uplot-$UPLOT.tgz" -C "$work" && mv "$work/package" "$work/uplot"
tar -xzf "$work/three-$THREE.tgz" -C "$work" && mv "$work/package" "$work/three"
tar -xzf "$work/swagger-ui-dist-$SWAGGER.tgz" -C "$work" && mv "$work/package" "$work/swagger-ui"
mkdir -p "$vendor/uplot" "$vendor/three/addons" "$vendor/swagger-ui"
cp "$work/uplot/dist/uPlot.iife.min.js" "$work/uplot/dist/uPlot.min.css" "$work/uplot/LICENSE" \
  "$vendor/uplot/"
cp "$work/three/build/three.module.js" "$work/three/build/three.core.js" "$work/three/LICENSE" \
  "$vendor/three/"
cp "$work/three/examples/jsm/controls/OrbitControls.js" "$vendor/three/addons/"
cp "$work/swagger-ui/"{swagger-ui-bundle.js,swagger-ui.css,favicon-32x32.png,LICENSE,NOTICE} \
  "$vendor/swagger-ui/"
cd "$vendor"
if [[ "${1:-}" == "--update" ]]; then
  find . -type f ! -name SHA256SUMS ! -name README.md | sort | xargs sha256sum >SHA256SUMS
else
  sha256sum --check --quiet SHA256SUMS && echo "vendored files match SHA256SUMS"
fi
