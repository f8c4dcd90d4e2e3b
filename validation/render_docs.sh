#!/usr/bin/env bash
# Regenerates the pictures in docs/images/ (run from the repository root after `make`).
set -euo pipefail
NIMBUS=${NIMBUS:-build/bin/nimbus}
SPP=${SPP:-512}
mkdir -p docs/images out
"$NIMBUS" render -o out/demo.exr --preview docs/images/demo.png --spp "$SPP" --quiet
"$NIMBUS" render scenes/disney_cloud.json -o out/disney_cloud.exr --preview docs/images/disney_cloud.png --spp "$SPP" --quiet
"$NIMBUS" render scenes/disney_cloud.json -o out/disney_cloud_mfs.exr --preview docs/images/disney_cloud_mfs.png --integrator mfs --spp 1 --quiet
"$NIMBUS" render scenes/sphere_hg.json -o out/sphere_hg.exr --preview docs/images/sphere_hg.png --spp "$SPP" --quiet
"$NIMBUS" render scenes/smoke_plume.json -o out/smoke_plume.exr --preview docs/images/smoke_plume.png --spp "$SPP" --quiet
echo "docs/images regenerated"
