#!/usr/bin/env bash
# Alternated auto-only runs for an A/B of auto (bench/auto_ab.py compares them): base, variant,
# base, variant, each over the study and/or the held-out MuJoCo models. The variant is the same
# build run with VARIANT_ENV set (a temporary switch in the code, removed before committing);
# this machine's speed drifts within minutes, so the sides alternate.
#
#   bench/auto_ab_runs.sh "LCS_AB=1" [study|heldout|both] [OUT_DIR]
#
# writes OUT_DIR/t_{s,h}_{0,1}_{1,2}.csv (s: study, h: held-out; 0: base, 1: variant; round).
set -euo pipefail
cd "$(dirname "$0")/.."
W=${W:-build/bench-study/devel/lib/lcp_contact_solver/work_precision}
T=1e-2,1e-3,1e-4,1e-5,1e-6,1e-7,1e-8,1e-9,1e-10
M=/usr/share/mujoco/model
L=$M/composite/cloth.xml,$M/composite/grid2pin.xml,$M/composite/loop.xml,$M/composite/softbox.xml,$M/hammock/hammock.xml,$M/humanoid/humanoid.xml,$M/mug/mug.xml,$M/slider_crank/slider_crank.xml,$M/tendon_arm/arm26.xml,$M/adhesion/active_adhesion.xml
VARIANT_ENV="$1"
WHAT=${2:-both}
OUT=${3:-/tmp/ab}
mkdir -p "$OUT"
for round in 1 2; do
  for side in 0 1; do
    if [ "$side" = 1 ]; then E="$VARIANT_ENV"; else E=""; fi
    if [ "$WHAT" != heldout ]; then
      env $E "$W" --solvers auto --tolerances $T --out "$OUT/t_s_${side}_$round.csv" --regret "$OUT/r.md" >/dev/null 2>&1
    fi
    if [ "$WHAT" != study ]; then
      env $E "$W" --solvers auto --tolerances $T --families mujoco --mujoco-models "$L" --mujoco-steps 300,1000 \
        --out "$OUT/t_h_${side}_$round.csv" --regret "$OUT/r.md" >/dev/null 2>&1
    fi
    echo "round $round side $side done $(date +%T)"
  done
done
