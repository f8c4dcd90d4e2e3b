#!/usr/bin/env bash
# make demo: the built-in cloud rendered by mfs, and beside it by pathtrace given the same time.
#   scripts/demo.sh BUILD_DIR OUT_DIR
set -euo pipefail
build=${1:-build}
out=${2:-out}
nimbus="$build/bin/nimbus"
mkdir -p "$out"

start=$(date +%s.%N)
"$nimbus" render --integrator mfs --spp 16 -o "$out/demo.exr" --preview "$out/demo.png" --quiet
end=$(date +%s.%N)
t=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.2f", b - a }')

# The path tracer gets the same wall-clock budget (set-up included), and as many passes as fit in it.
summary=$("$nimbus" render --integrator pathtrace --spp 65536 --time "$t" -o "$out/demo_pathtrace.exr" \
  --preview "$out/demo_pathtrace.png" 2>&1 | tail -n1)
spp=$(echo "$summary" | sed -n 's/.* \([0-9]*\) spp in .*/\1/p')

echo "nimbus demo: the built-in cloud (320x240, sun and sky)"
echo "  mfs        16 spp in ${t} s -> $out/demo.png ($out/demo.exr)"
echo "  pathtrace  ${spp:-?} spp in the same ${t} s -> $out/demo_pathtrace.png ($out/demo_pathtrace.exr)"
echo "  mfs is the multiple-forward-scattering approximation; pathtrace is the unbiased reference,"
echo "  grainy at equal time (docs/validation/render.md measures both against converged references)."
