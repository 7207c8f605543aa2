#!/usr/bin/env bash
# Robustness check: every corpus mesh (../shared/corpus, up to 120k faces)
# repaired as it is and after `polyheal perturb` with each kind (near-coplanar,
# near-collinear, duplicates, slivers: 10% of the faces, epsilon 1e-9, seed
# PERTURB_SEED, default 7). A perturbation of a CAD export should not make its
# repair worse: prints one line per perturbed repair that errs (exit 2 or a
# crash or time-out), exits 1 where the unperturbed one exits 0, or moves the
# surface more than twice as far (and 0.1% of the diagonal more); then a count.
# Not a test (it takes ~20 minutes on 2 cores) and not timed; a tool for
# finding what a benchmark's fixed inputs do not show.
#
#   scripts/perturb_check.sh                 # build, then check
#   PERTURB_SEED=3 scripts/perturb_check.sh  # other perturbations
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/build.sh" --target polyheal >/dev/null
bin="$root/build/polyheal"; corpus="$root/../shared/corpus"
seed=${PERTURB_SEED:-7}
work="$root/build/perturb_check"; rm -rf "$work"; mkdir -p "$work"
json_num() { sed -n "s/.*\"$1\": \([-0-9.e+]*\).*/\1/p" "$2" | head -1; }
# repaired IN NAME: repairs IN into $work/NAME.off; prints "exit moved%" ("err"
# for an exit above 1 or a time-out)
repaired() {
  local code=0
  timeout 300 "$bin" repair --json --overwrite "$1" -o "$work/$2.off" >"$work/$2.json" 2>"$work/$2.err" || code=$?
  if [ "$code" -gt 1 ]; then echo "err -"; return; fi
  local moved max
  moved=$(json_num surface_moved "$work/$2.json"); max=$(json_num max_deviation "$work/$2.json")
  echo "$code $(awk -v m="$moved" -v x="$max" 'BEGIN { printf "%.4g", 100 * 0.01 * m / x }')"
}
worse=0; checked=0
for f in "$corpus"/*; do
  case "$f" in *.off|*.obj|*.stl|*.STL|*.ply) ;; *) continue ;; esac
  name=$(basename "$f")
  faces=$(awk -F'\t' -v n="$name" '$1 == n { print $6 }' "$corpus/MANIFEST.tsv")
  [ -n "$faces" ] && [ "$faces" -gt 120000 ] && continue
  read -r base_exit base_moved <<<"$(repaired "$f" "$name.base")"
  for kind in near-coplanar near-collinear duplicates slivers; do
    p="$work/$name.$kind.in.off"
    "$bin" perturb "$f" -o "$p" --kind "$kind" --seed "$seed" --overwrite >/dev/null 2>&1 || continue
    read -r e m <<<"$(repaired "$p" "$name.$kind")"
    checked=$((checked + 1))
    bad=""
    if [ "$e" = err ]; then bad="error: $(tail -c 200 "$work/$name.$kind.err" | tr '\n' ' ')"
    elif [ "$base_exit" = 0 ] && [ "$e" != 0 ]; then bad="exit 0 -> $e"
    elif awk -v a="$base_moved" -v b="$m" 'BEGIN { exit !(a != "-" && b > 2 * a && b > a + 0.1) }'; then
      bad="moved ${base_moved}% -> ${m}%"
    fi
    [ -n "$bad" ] && { worse=$((worse + 1)); echo "$name $kind: $bad"; }
  done
done
echo "$worse of $checked perturbed repairs worse than the unperturbed one (seed $seed; outputs in $work)"
