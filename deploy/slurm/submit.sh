#!/usr/bin/env bash
# Submit an `orbitlash margins` run to Slurm: a job array of K shards and a merge job
# that starts when every shard succeeded. The merged report lands in OUT/margins.json.
#
#   deploy/slurm/submit.sh SCENARIO --samples N --seed S --shards K --out DIR [-- MARGINS-ARGS...]
#
# Prints the two job ids. The binary: $ORBITLASH_BIN when set, else `orbitlash` on the
# PATH, else this clone's release build (`cargo build --release`).
set -euo pipefail
usage() { echo "usage: $0 SCENARIO --samples N --seed S --shards K --out DIR [-- MARGINS-ARGS...]" >&2; exit 2; }
[ $# -ge 1 ] || usage
scenario=$1; shift
samples='' seed='' shards='' out='' extra=''
while [ $# -gt 0 ]; do
  case "$1" in
    --samples) samples=${2:-}; shift 2 ;;
    --seed) seed=${2:-}; shift 2 ;;
    --shards) shards=${2:-}; shift 2 ;;
    --out) out=${2:-}; shift 2 ;;
    --) shift; extra="$*"; break ;;
    *) echo "unknown argument: $1" >&2; usage ;;
  esac
done
[ -n "$samples" ] && [ -n "$seed" ] && [ -n "$shards" ] && [ -n "$out" ] || usage
case "$shards" in ''|*[!0-9]*) echo "--shards must be a whole number" >&2; exit 2 ;; esac
[ "$shards" -ge 1 ] || { echo "--shards must be at least 1" >&2; exit 2; }
[ -f "$scenario" ] || { echo "no such scenario file: $scenario" >&2; exit 2; }

here=$(cd "$(dirname "$0")" && pwd)
if [ -n "${ORBITLASH_BIN:-}" ]; then
  bin=$ORBITLASH_BIN
elif command -v orbitlash >/dev/null 2>&1; then
  bin=$(command -v orbitlash)
else
  bin="${CARGO_TARGET_DIR:-$here/../../target}/release/orbitlash"
fi
[ -x "$bin" ] || { echo "no orbitlash binary at $bin (set ORBITLASH_BIN or run cargo build --release)" >&2; exit 2; }
bin=$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")

mkdir -p "$out"
out=$(cd "$out" && pwd)
scenario=$(cd "$(dirname "$scenario")" && pwd)/$(basename "$scenario")
rm -f "$out"/shard-*.json "$out/margins.json"

# Validate before submitting anything: a bad scenario fails here, not in K jobs.
"$bin" check "$scenario" >/dev/null

export ORBITLASH_BIN="$bin" SCENARIO="$scenario" SAMPLES="$samples" SEED="$seed" SHARDS="$shards" OUT="$out" EXTRA="$extra"
array=$(sbatch --parsable --chdir="$out" --array="0-$((shards - 1))" --export=ALL "$here/margins.sbatch")
array=${array%%;*}
shard_files=$(for ((i = 0; i < shards; i++)); do printf '%s ' "$out/shard-$i.json"; done)
merge=$(sbatch --parsable --chdir="$out" --job-name=orbitlash-merge --output=%x-%j.out \
  --dependency="afterok:$array" --kill-on-invalid-dep=yes \
  --wrap="'$bin' merge $shard_files --json '$out/margins.json'")
merge=${merge%%;*}
echo "array job $array ($shards shards), merge job $merge; the report: $out/margins.json"
