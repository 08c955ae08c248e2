#!/usr/bin/env bash
# Renders a fixed set of fixed-budget images and statistics with one `tempera` binary into a
# folder, or compares two such folders: a refactoring must leave every image byte-identical
# and every statistic identical (timings aside).
#   experiments/identical.sh render BINARY DIR
#   experiments/identical.sh compare DIR_A DIR_B
set -euo pipefail
case "${1:-}" in
render)
  bin=$2 dir=$3
  mkdir -p "$dir"
  common=(--resolution 48x36 --seed 7 --threads 2 --quiet)
  runs=(
    "path --spp 8"
    "bdpt --spp 4"
    "bdpt --spp 2 --mis balance"
    "pssmlt --mpp 4 --bootstrap 4000"
    "mmlt --mpp 4 --bootstrap 4000"
    "mmlt --mpp 4 --bootstrap 4000 --hybrid 0.5"
    "tempered --mpp 4 --bootstrap 4000 --burn-in 40"
    "tempered --mpp 4 --bootstrap 4000 --burn-in 40 --no-reuse-replicas"
    "tempered --mpp 4 --bootstrap 4000 --burn-in 40 --swap equi-energy"
    "tempered --mpp 4 --bootstrap 4000 --burn-in 40 --swap equi-energy --no-reuse-replicas"
    "tempered --mpp 4 --bootstrap 4000 --swap permutation --replicas 4"
    "tempered --mpp 4 --bootstrap 4000 --swap permutation --replicas 4 --no-reuse-replicas"
    "tempered --mpp 4 --bootstrap 4000 --ladder 0.05,0.3 --tempered-mis roughened --swap-every 2"
    "tempered --mpp 4 --bootstrap 4000 --replicas 1"
  )
  # Real scenes (pbrt-v4 and Mitsuba files) when ../shared is beside the checkout.
  shared=$(dirname "$0")/../../shared/scenes
  if [ -d "$shared" ]; then
    runs+=(
      "mmlt $shared/veach-ajar/pbrt-v4/scene-v4.pbrt --mpp 2 --bootstrap 4000"
      "tempered $shared/veach-ajar/pbrt-v4/scene-v4.pbrt --mpp 2 --bootstrap 4000 --burn-in 20"
      "bdpt $shared/veach-mis/mitsuba/scene_v0.6.xml --spp 2"
      "tempered $shared/veach-mis/mitsuba/scene_v0.6.xml --mpp 2 --bootstrap 4000 --burn-in 20 --swap permutation"
    )
  fi
  i=0
  for r in "${runs[@]}"; do
    i=$((i + 1))
    read -r -a args <<<"$r"
    "$bin" render --integrator "${args[@]}" "${common[@]}" -o "$dir/$i.exr" --stats "$dir/$i.json"
    echo "$i: $r" >>"$dir/runs.txt"
  done
  ;;
compare)
  a=$2 b=$3 status=0
  strip() { python3 -c 'import json,sys
def walk(v):
    if isinstance(v, dict):
        return {k: walk(x) for k, x in v.items() if not k.endswith("seconds") and k not in ("rays_per_second", "mutations_per_second")}
    if isinstance(v, list):
        return [walk(x) for x in v]
    return v
print(json.dumps(walk(json.load(open(sys.argv[1]))), indent=1, sort_keys=True))' "$1"; }
  for f in "$a"/*.exr; do
    n=$(basename "$f" .exr)
    cmp -s "$f" "$b/$n.exr" || { echo "image $n differs: $(grep "^$n:" "$a/runs.txt")"; status=1; }
    diff <(strip "$a/$n.json") <(strip "$b/$n.json") >/dev/null || { echo "stats $n differ: $(grep "^$n:" "$a/runs.txt")"; status=1; }
  done
  [ $status = 0 ] && echo "all $(ls "$a"/*.exr | wc -l) images and statistics identical"
  exit $status
  ;;
*) echo "usage: $0 render BINARY DIR | compare DIR_A DIR_B" >&2; exit 2 ;;
esac
