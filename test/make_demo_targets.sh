#!/usr/bin/env bash
# `make demo` builds only what the demo runs: a dry run (make -n) of the demo target names
# exactly the three programs and never the tests. Usage: test/make_demo_targets.sh SOURCE_DIR
set -euo pipefail
src="${1:-$(cd "$(dirname "$0")/.." && pwd)}"
plan="$(make -n -C "$src" demo 2>/dev/null | grep -- 'cmake --build' || true)"
echo "$plan"
if [ -z "$plan" ]; then echo "FAIL: make -n demo builds nothing"; exit 1; fi
if echo "$plan" | grep -q -- '--target tests'; then echo "FAIL: make demo builds the tests"; exit 1; fi
if ! echo "$plan" | grep -q -- '--target lcp_solve contact_solver_node scene_simulator$'; then
  echo "FAIL: make demo does not build exactly lcp_solve contact_solver_node scene_simulator"; exit 1
fi
if [ "$(echo "$plan" | wc -l)" -ne 1 ]; then echo "FAIL: make demo runs more than one build"; exit 1; fi
echo "OK: make demo builds only the demo's programs"
