#!/usr/bin/env bash
# Submits nimbus renders to Slurm (docs/farm.md).
#   submit.sh sequence SCENE.json FRAMES 'OUT/shot.$F4.exr' [sbatch options --] [render options]
#       a job array, one frame per task (FRAMES: 1-240, 1-240x2, 1,3,5 as render --frames)
#   submit.sh split SCENE.json OUT.exr TX TY RANGES SPP [sbatch options --] [render options]
#       one heavy frame as TX x TY tiles times RANGES sample ranges (of SPP samples in all), a job array,
#       and a merge job that runs when every part succeeded (--dependency=afterok)
# Prints the job ids. Re-running the same command submits again: tasks whose output is done exit at
# once, killed ones resume their partial image (task.sh). NIMBUS (default: nimbus on PATH, else the build)
# names the program the nodes run; paths must be visible from the nodes (a shared file system).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
nimbus=${NIMBUS:-$(command -v nimbus || echo "$here/../../build/bin/nimbus")}
nimbus=$(realpath "$nimbus")
mode=${1:?sequence|split}
shift
sb=()
split_sbatch() {  # sbatch options up to a lone --, the rest for nimbus render
  render=()
  local seen=0
  for a in "$@"; do [[ $a == -- ]] && seen=1; done
  if ((seen)); then
    while [[ $1 != -- ]]; do sb+=("$1"); shift; done
    shift
  fi
  render=("$@")
  rargs=$(printf ' %q' "${render[@]}")  # quoted for the task's shell
  [[ ${#render[@]} -gt 0 ]] || rargs=""
}
case $mode in
sequence)
  scene=$(realpath "${1:?SCENE}"); frames=${2:?FRAMES}; out=${3:?OUT}
  shift 3
  split_sbatch "$@"
  [[ $out == *'$F'* ]] || { echo "submit.sh: OUT must hold \$F or \$F4" >&2; exit 2; }
  out=$(realpath -m "$out")
  mkdir -p "$(dirname "$out")/logs"
  array=${frames//x/:}  # Slurm writes steps as A-B:S
  # Each task: the frame's output name, then task.sh.
  sbatch --parsable --array="$array" --job-name=nimbus-seq -o "$(dirname "$out")/logs/%A_%a.log" \
    "${sb[@]}" --wrap "'$here/task.sh' '$nimbus' '$out' \$SLURM_ARRAY_TASK_ID '$scene' $rargs"
  ;;
split)
  scene=$(realpath "${1:?SCENE}"); out=$(realpath -m "${2:?OUT}"); tx=${3:?TX}; ty=${4:?TY}; k=${5:?RANGES}; spp=${6:?SPP}
  shift 6
  split_sbatch "$@"
  read -r w h < <(python3 -c 'import json,sys; c=json.load(open(sys.argv[1]))["camera"]; print(c["width"], c["height"])' "$scene")
  for a in "${render[@]}"; do
    [[ $a == --res ]] && { echo "submit.sh split: give the size in the scene (or --set camera.width=...), not --res" >&2; exit 2; }
  done
  parts="${out%.*}.parts"
  mkdir -p "$parts/logs"
  n=$((tx * ty * k))
  # Task t: tile t / k (row-major), sample range t % k; the ranges split SPP as evenly as they can.
  jid=$(sbatch --parsable --array=0-$((n - 1)) --job-name=nimbus-part -o "$parts/logs/%A_%a.log" "${sb[@]}" --wrap "
    t=\$SLURM_ARRAY_TASK_ID; tile=\$((t / $k)); r=\$((t % $k)); ix=\$((tile % $tx)); iy=\$((tile / $tx))
    x0=\$((ix * $w / $tx)); x1=\$(((ix + 1) * $w / $tx)); y0=\$((iy * $h / $ty)); y1=\$(((iy + 1) * $h / $ty))
    s0=\$((r * $spp / $k)); s1=\$(((r + 1) * $spp / $k))
    '$here/task.sh' '$nimbus' '$parts'/part_\${ix}_\${iy}_\${r}.exr - '$scene' --region \$x0,\$y0,\$x1,\$y1 \
      --samples \$s0:\$((s1 - s0)) $rargs")
  echo "$jid"
  sbatch --parsable --dependency=afterok:"$jid" --job-name=nimbus-merge -o "$parts/logs/merge_%j.log" "${sb[@]}" \
    --wrap "'$nimbus' merge --quiet '$parts'/part_*.exr -o '$out'"
  ;;
*)
  echo "usage: submit.sh sequence|split ..." >&2
  exit 2
  ;;
esac
