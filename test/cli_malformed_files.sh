#!/bin/sh
# Runs `lcp_solve FILE` on every file of a directory of malformed problem files and checks
# that each gives exit status 1 (not a crash: a signal gives >= 128), one stderr line
# "lcp_solve: FILE: reason", nothing on stdout, within 10 s.
# Usage: cli_malformed_files.sh LCP_SOLVE DIR
set -u
solver="$1"
dir="$2"
failed=0
count=0
for file in "$dir"/*.dat "$dir"/*.hdf5; do
  [ -e "$file" ] || continue
  count=$((count + 1))
  out=$(mktemp) err=$(mktemp)
  timeout 10 "$solver" "$file" >"$out" 2>"$err"
  status=$?
  lines=$(wc -l <"$err")
  if [ "$status" -ne 1 ] || [ "$lines" -ne 1 ] || [ -s "$out" ] || ! grep -q "^lcp_solve: $file: " "$err"; then
    echo "FAIL $file: exit $status, $lines stderr lines:" >&2
    cat "$err" "$out" >&2
    failed=$((failed + 1))
  else
    echo "ok   $(basename "$file"): $(cat "$err")"
  fi
  rm -f "$out" "$err"
done
echo "$count malformed files, $failed failures"
[ "$count" -gt 0 ] && [ "$failed" -eq 0 ]
