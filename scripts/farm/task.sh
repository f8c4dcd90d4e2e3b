#!/usr/bin/env bash
# One farm task (run by Slurm, or by hand): renders OUT unless it is done already, resuming a partial
# image where an earlier try of the task was stopped.
#   task.sh NIMBUS OUT FRAME|- [nimbus render arguments without -o]
# With a FRAME, OUT is a pattern ($F, $F4 as render --frames) and the task renders that frame.
# OUT done: the file exists and its header says nimbus/partial and nimbus/time_limited false (nimbus
# writes atomically, so a file is whole or absent). OUT.partial.exr present (a try stopped by SIGTERM:
# scancel, the time limit, a preempted node): resumed with `render --resume`, bit-identical to one render.
set -uo pipefail
nimbus=${1:?NIMBUS}
pattern=${2:?OUT}
frame=${3:?FRAME or -}
shift 3
out=$pattern
if [[ $frame != - ]]; then
  while [[ $out =~ \$F([1-9]) ]]; do
    w=${BASH_REMATCH[1]}
    out=${out/"\$F$w"/$(printf "%0${w}d" "$frame")}
  done
  out=${out//\$F/$frame}
fi
partial="${out%.*}.partial.${out##*.}"
header=$("$nimbus" info "$out" 2>/dev/null || true)
if grep -qx 'nimbus/partial false' <<<"$header" && grep -qx 'nimbus/time_limited false' <<<"$header"; then
  echo "task: $out is done"
  exit 0
fi
if [[ -f $partial ]]; then
  echo "task: resuming $partial"
  exec "$nimbus" render --quiet --resume "$partial" -o "$out"
fi
if [[ -n $header ]]; then  # a time-limited image: continue it to the spp it asked for
  echo "task: resuming $out"
  exec "$nimbus" render --quiet --resume "$out" -o "$out"
fi
if [[ $frame != - ]]; then
  exec "$nimbus" render --quiet "$@" --frames "$frame" -o "$pattern"
fi
exec "$nimbus" render --quiet "$@" -o "$out"
