#!/usr/bin/env bash
# `polyheal repair` on every real mesh of the corpus (fixtures/corpus, a copy
# of ../shared/corpus) and on every fixture: each run must end with a verdict
# (exit 0 or 1, never an error or a crash) and write an output that an
# independent `polyheal check` certifies clean; the report's own exit code and
# certified flag must agree with that check.
# Exceptions (none at present) go in `exceptions` with their reason.
set -u
bin=$1; src=$2
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
declare -A exceptions=()
one() {  # one INPUT -> prints "PASS name" or "FAIL name: why"
  local in=$1 name; name=$(basename "$1")
  local out="$tmp/$name.out.off" json="$tmp/$name.json"
  "$bin" repair "$in" -o "$out" --json >"$json" 2>"$tmp/$name.err"; local code=$?
  if [ "$code" -gt 1 ]; then echo "FAIL $name: repair exit $code: $(tail -c 300 "$tmp/$name.err")"; return; fi
  "$bin" check "$out" >"$tmp/$name.check" 2>&1; local check=$?
  if [ "$check" -ne 0 ]; then echo "FAIL $name: output not certified: $(tail -n 3 "$tmp/$name.check")"; return; fi
  grep -q '"certified": true' "$json" || { echo "FAIL $name: report does not say certified"; return; }
  grep -q "\"exit_code\": $code" "$json" || { echo "FAIL $name: report exit code differs from $code"; return; }
  echo "PASS $name (exit $code)"
}
export -f one; export bin tmp
inputs=$(ls "$src"/fixtures/corpus/*.{off,obj,stl,STL,ply} "$src"/fixtures/*.{off,obj,stl,ply} 2>/dev/null)
results=$(printf '%s\n' $inputs | xargs -P 2 -I{} bash -c 'one "$@"' _ {})
fails=0; passes=0; known=0
while read -r status name rest; do
  [ -z "$status" ] && continue
  base=${name%:}
  if [ "$status" = PASS ]; then passes=$((passes+1));
  elif [ -n "${exceptions[$base]:-}" ]; then known=$((known+1)); echo "known exception $base: ${exceptions[$base]}";
  else fails=$((fails+1)); echo "$status $name $rest"; fi
done <<< "$results"
total=$(printf '%s\n' $inputs | wc -l)
echo "$passes of $total certified, $fails failed"
# Every input accounted for (a listing that found nothing cannot pass).
[ "$fails" -eq 0 ] && [ $((passes + known)) -eq "$total" ] && [ "$total" -ge 90 ]
