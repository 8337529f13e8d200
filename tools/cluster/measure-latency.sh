#!/usr/bin/env bash
# measure-latency.sh - per-job and per-task start-up cost of a Slurm cluster.
#
#   SLURM_CONF=DIR/slurm.conf tools/cluster/measure-latency.sh [REPS] [ARRAY_N]
#
# Submits trivial jobs (`true`) and times, with a 50 ms poll of squeue, from just
# before sbatch until the job (or all its array tasks) left squeue's pending/running/
# completing states. Prints one line per run and the median of each kind:
#   single  one job                                   (sbatch -> done)
#   array   an array of ARRAY_N tasks (default 16)    (sbatch -> all done)
#   chain   job -> array of 4 (afterok) -> job (afterok), as a bake unit graph
# Jobs write no output (-o /dev/null). Meant for the one-node test cluster of
# test-cluster.sh; results depend on SchedulerParameters and the node's CPU count.
set -euo pipefail
REPS=${1:-5}
AN=${2:-16}
: "${SLURM_CONF:?set SLURM_CONF (eval \"\$(tools/cluster/test-cluster.sh start DIR)\")}"

now() { date +%s.%N; }
# wait until none of the given job ids is pending, running or completing
wait_gone() {
    while [[ -n $(squeue -h -r -j "$1" -t PD,R,CG,CF -o %i 2>/dev/null) ]]; do sleep 0.05; done
}
median() { sort -n | awk '{a[NR]=$1} END {if (NR % 2) print a[(NR+1)/2]; else printf "%.3f\n", (a[NR/2]+a[NR/2+1])/2}'; }

declare -a S A C
for ((r = 0; r < REPS; r++)); do
    t0=$(now)
    j=$(sbatch --parsable -o /dev/null -J lat-single --wrap true)
    wait_gone "$j"
    S+=("$(awk -v a="$(now)" -v b="$t0" 'BEGIN {printf "%.3f", a - b}')")

    t0=$(now)
    j=$(sbatch --parsable -o /dev/null -J lat-array --array=0-$((AN - 1)) --wrap true)
    wait_gone "$j"
    A+=("$(awk -v a="$(now)" -v b="$t0" 'BEGIN {printf "%.3f", a - b}')")

    t0=$(now)
    j1=$(sbatch --parsable -o /dev/null -J lat-voxel --wrap true)
    j2=$(sbatch --parsable -o /dev/null -J lat-recv --array=0-3 --dependency=afterok:$j1 --wrap true)
    j3=$(sbatch --parsable -o /dev/null -J lat-merge --dependency=afterok:$j2 --wrap true)
    wait_gone "$j1,$j2,$j3"
    C+=("$(awk -v a="$(now)" -v b="$t0" 'BEGIN {printf "%.3f", a - b}')")
    printf 'run %d: single %.3f s  array(%d) %.3f s  chain %.3f s\n' "$r" "${S[-1]}" "$AN" "${A[-1]}" "${C[-1]}"
done
printf 'median of %d: single %.3f s  array(%d) %.3f s  chain %.3f s\n' "$REPS" \
    "$(printf '%s\n' "${S[@]}" | median)" "$AN" "$(printf '%s\n' "${A[@]}" | median)" \
    "$(printf '%s\n' "${C[@]}" | median)"
