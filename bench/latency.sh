#!/usr/bin/env bash
# Latency and rate of the live contact solver (issue #8; docs/BENCHMARKS.md "Latency and
# rate"; a benchmark, not a test). For each configuration it starts the solver with
# config/default.yaml (+ initial_guess set per configuration), runs latency_bench against it
# (bench/latency.cpp: round trips with one pair in flight, then N in flight for a while), and
# stops it again.
#
#   bench/latency.sh [--build DIR] [--csv OUT.csv] [--modes reference,node,nodelet,inproc]
#                    [--starts cold,warm] [--markers 0,1] [--bases 5,16] [--count N]
#                    [--rate-seconds S] [--latency-seconds S] [--inflight 1,4] [--param NAME=VALUE]...
#                    [--pace HZ,...] [--pace-seconds S] [--pin CPUS]
#
# Modes: reference  no solver process: the node's cycle in-process, part by part, on the same
#                messages (latency_bench --reference-only; CSV <csv>_reference.csv)
#        node    contact_solver_node, its own process (messages over TCP, serialized)
#        nodelet nodelet manager + `nodelet load lcp_contact_solver/ContactSolverNodelet`: the
#                publisher (latency_bench) is another process, so messages still go over TCP
#        inproc  the nodelet loaded into latency_bench itself (nodelet::Loader): publisher and
#                solver share the process and messages pass as shared pointers
# Starts: cold  initial_guess=false: every cycle a cold solve of the same problem
#         warm  initial_guess=true (the default): the same problem again with the same contact
#               ids, so after the first cycle the warm start is already the answer
# Markers: 1 runs a second process subscribed to /contact_solver/markers (node mode only).
# --pace 1000: after the rate phases, a phase publishing a pair every 1 ms on a fixed clock
#         (paced_1000, --pace-seconds long): the rate a simulator at 1 kHz gets answered.
# --pin CPUS: the solver process (node, nodelet manager) runs under `taskset -c CPUS`.
# Defaults: build folder ./build/bench-runtime, all four modes and both starts, markers 0 and 1 (node),
# CSV bench/results/latency.csv (replaced), the tables in the .log beside it (`--modes
# reference` alone writes latency_reference.{csv,log} and leaves latency.{csv,log} alone). A private
# roscore on a free port, logs in <build>/ros_home; everything started is stopped on exit.
set -uo pipefail
export PATH=/usr/bin:/bin:$PATH  # Debian's python3 first: a pyenv python3 breaks rospy tools

here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$here/build/bench-runtime"
csv="$here/bench/results/latency.csv"
modes="reference,node,nodelet,inproc"
starts="cold,warm"
markers_list="0,1"
bench_args=()
params=()
pin=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --csv) csv="$2"; shift 2 ;;
    --modes) modes="$2"; shift 2 ;;
    --starts) starts="$2"; shift 2 ;;
    --markers) markers_list="$2"; shift 2 ;;
    --bases | --balls | --count | --rate-seconds | --latency-seconds | --inflight | --steps | --warmup | --pace | --pace-seconds) bench_args+=("$1" "$2"); shift 2 ;;
    --pin) pin=(taskset -c "$2"); shift 2 ;;
    --param) params+=("$2"); shift 2 ;;
    -h | --help) sed -n '2,30p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "latency.sh: unknown option $1 (--help)" >&2; exit 2 ;;
  esac
done
log="${csv%.csv}.log"
[ "$modes" = reference ] && log="${csv%.csv}_reference.log"  # a reference-only run keeps the other files
# The devel space: the build folder's own (build/bench-runtime), else ./devel (the main build).
devel="${DEVEL_DIR:-$build/devel}"
[ -f "$devel/setup.bash" ] || devel="$here/devel"
bin="$devel/lib/lcp_contact_solver"
for exe in contact_solver_node latency_bench; do
  if [ ! -x "$bin/$exe" ]; then
    echo "latency.sh: $bin/$exe not found: cmake --build $build --target latency_bench" >&2
    exit 1
  fi
done
nodelet_exe=/usr/lib/nodelet/nodelet
if [[ ",$modes," == *,nodelet,* ]] && [ ! -x "$nodelet_exe" ]; then
  echo "latency.sh: $nodelet_exe not found (Debian package libnodeletlib-tools)" >&2
  exit 1
fi

build="$(cd "$build" && pwd)"
bin="$devel/lib/lcp_contact_solver"
export ROS_HOME="$build/ros_home"
export ROS_LOG_DIR="$ROS_HOME/log"
mkdir -p "$ROS_LOG_DIR" "$(dirname "$csv")"
[ "$modes" = reference ] || rm -f "$csv"
[[ ",$modes," == *,reference,* ]] && rm -f "${csv%.csv}_reference.csv"
set +u
# shellcheck disable=SC1091
source "$devel/setup.bash"
set -u
port="$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')"
export ROS_MASTER_URI="http://localhost:$port"

# Each process in its own session (setsid), so a stop reaches its children too.
roscore_pid="" solver_pid="" loader_pid="" sink_pid=""
# shellcheck disable=SC2317  # reached from the EXIT trap
stop() {  # stop PID: SIGINT to its group, up to 5 s, then SIGKILL
  [ -n "$1" ] || return 0
  kill -INT -- "-$1" 2>/dev/null || return 0
  for _ in $(seq 50); do kill -0 "$1" 2>/dev/null || return 0; sleep 0.1; done
  kill -KILL -- "-$1" 2>/dev/null || true
}
# shellcheck disable=SC2317
stop_solver() {
  stop "$sink_pid"; stop "$loader_pid"; stop "$solver_pid"
  sink_pid="" loader_pid="" solver_pid=""
}
# shellcheck disable=SC2317
cleanup() { stop_solver; stop "$roscore_pid"; }
trap cleanup EXIT
trap 'exit 130' INT TERM

setsid roscore -p "$port" >"$ROS_LOG_DIR/latency_roscore.out" 2>&1 </dev/null &
roscore_pid=$!
for _ in $(seq 100); do rosparam list >/dev/null 2>&1 && break; sleep 0.2; done
rosparam list >/dev/null 2>&1 || { echo "latency.sh: no master on port $port" >&2; exit 1; }

{
  echo "latency.sh: $(date -u +%FT%TZ), $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg) at the start"
  echo "latency.sh: modes $modes, starts $starts, markers $markers_list, ${bench_args[*]:-default sizes}, ${params[*]:-default parameters}"
} | tee "$log"

status=0
IFS=, read -r -a mode_arr <<<"$modes"
IFS=, read -r -a start_arr <<<"$starts"
IFS=, read -r -a marker_arr <<<"$markers_list"
for mode in "${mode_arr[@]}"; do
  for start in "${start_arr[@]}"; do
    for markers in "${marker_arr[@]}"; do
      [ "$markers" = 1 ] && [ "$mode" != node ] && continue
      rosparam delete /contact_solver >/dev/null 2>&1
      rosparam load "$here/config/default.yaml" /contact_solver || exit 1
      rosparam set /contact_solver/initial_guess "$([ "$start" = warm ] && echo true || echo false)"
      for p in "${params[@]}"; do rosparam set "/contact_solver/${p%%=*}" "${p#*=}" || exit 1; done
      extra=()
      case "$mode" in
        node)
          setsid "${pin[@]}" "$bin/contact_solver_node" __name:=contact_solver >"$ROS_LOG_DIR/latency_node.out" 2>&1 </dev/null &
          solver_pid=$!
          extra=(--solver-pid "$solver_pid") ;;
        nodelet)
          setsid "${pin[@]}" "$nodelet_exe" manager __name:=lcs_manager >"$ROS_LOG_DIR/latency_manager.out" 2>&1 </dev/null &
          solver_pid=$!
          setsid "$nodelet_exe" load lcp_contact_solver/ContactSolverNodelet lcs_manager __name:=contact_solver \
            >"$ROS_LOG_DIR/latency_loader.out" 2>&1 </dev/null &
          loader_pid=$!
          extra=(--solver-pid "$solver_pid") ;;
        inproc)
          extra=(--in-process-nodelet) ;;
        reference)
          [ "$markers" = 1 ] && continue
          echo "== reference (in-process cycle by part), $start start; load $(cut -d' ' -f1-3 /proc/loadavg)" | tee -a "$log"
          "$bin/latency_bench" --reference-only --out "${csv%.csv}_reference.csv" "${bench_args[@]}" \
            2>>"$ROS_LOG_DIR/latency_bench.err" | tee -a "$log"
          [ "${PIPESTATUS[0]}" -eq 0 ] || { echo "latency.sh: latency_bench --reference-only failed" | tee -a "$log"; status=1; }
          continue ;;
        *) echo "latency.sh: unknown mode $mode" >&2; exit 2 ;;
      esac
      if [ "$markers" = 1 ]; then
        setsid "$bin/latency_bench" --sink /contact_solver/markers >"$ROS_LOG_DIR/latency_sink.out" 2>&1 </dev/null &
        sink_pid=$!
      fi
      echo "== $mode, $start start, markers subscriber $markers; load $(cut -d' ' -f1-3 /proc/loadavg)" | tee -a "$log"
      "$bin/latency_bench" --label "$mode" --markers "$markers" --out "$csv" "${extra[@]}" "${bench_args[@]}" \
        2>>"$ROS_LOG_DIR/latency_bench.err" | tee -a "$log"
      rc=${PIPESTATUS[0]}
      [ "$rc" -eq 0 ] || { echo "latency.sh: latency_bench failed ($rc) in $mode/$start/markers $markers" | tee -a "$log"; status=1; }
      if [ -n "$solver_pid" ] && ! kill -0 "$solver_pid" 2>/dev/null; then
        echo "latency.sh: the solver died (see $ROS_LOG_DIR)" | tee -a "$log"; status=1
      fi
      if [ "$rc" -ne 0 ]; then tail -n 5 "$ROS_LOG_DIR/latency_bench.err" >&2; fi
      if [ -n "$sink_pid" ]; then
        stop "$sink_pid"
        sink_pid=""
        tail -n 1 "$ROS_LOG_DIR/latency_sink.out" | tee -a "$log"
      fi
      stop_solver
    done
  done
done
echo "latency.sh: load average $(cut -d' ' -f1-3 /proc/loadavg) at the end; CSV $csv" | tee -a "$log"
exit $status
