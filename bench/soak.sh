#!/usr/bin/env bash
# Soak benchmark (issue #7; a benchmark, not a test): contact_solver_node fed by soak_feeder
# (a bag's contact/compliance pairs replayed in a loop, fresh stamps) at a fixed rate for
# minutes, the node's resident memory (VmRSS, /proc/<pid>/status) sampled once per second.
#
#   bench/soak.sh [--build DIR] [--duration S] [--rate HZ] [--bag BAG] [--csv OUT.csv]
#                 [--param NAME=VALUE]... [--pin CPUS]
#
# Defaults: build folder ./build (contact_solver_node and soak_feeder built there, e.g. by
# `make soak`), 300 s, 1000 Hz, test/data/box_stack.bag, bench/results/soak_rss_<bag>.csv.
# Writes the CSV (time_s,rss_kib,forces_received; t = 0 when the feeder starts) and the
# feeder's output plus the summary beside it (.log). Runs its own roscore on a free port,
# logs in <build>/ros_home, node parameters from config/default.yaml (--param overrides one,
# e.g. --param queue_size=100); stops all it started.
# Summary: RSS at 10 s, at the end, max, least-squares slope over the second half (KiB/min).
# Exit status 0 when the feeder ran to its end and the node survived.
set -uo pipefail
export PATH=/usr/bin:/bin:$PATH  # Debian's python3 first: a pyenv python3 breaks rospy tools

here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$here/build"
duration=300
rate=1000
bag="$here/test/data/box_stack.bag"
csv=""
params=()
pin=""
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --duration) duration="$2"; shift 2 ;;
    --rate) rate="$2"; shift 2 ;;
    --bag) bag="$2"; shift 2 ;;
    --csv) csv="$2"; shift 2 ;;
    --param) params+=("$2"); shift 2 ;;
    --pin) pin="$2"; shift 2 ;;  # the node under taskset -c CPUS (e.g. 1: one core)
    -h | --help) sed -n '2,17p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "soak: unknown option $1 (--help)" >&2; exit 2 ;;
  esac
done
[ -n "$csv" ] || csv="$here/bench/results/soak_rss_$(basename "$bag" .bag).csv"
log="${csv%.csv}.log"
# The main build's devel space is ./devel (Makefile); another build folder keeps its own.
devel="${DEVEL_DIR:-$build/devel}"
[ -f "$devel/setup.bash" ] || devel="$here/devel"
bin="$devel/lib/lcp_contact_solver"
for exe in contact_solver_node soak_feeder; do
  if [ ! -x "$bin/$exe" ]; then
    echo "soak: $bin/$exe not found: cmake --build $build --target contact_solver_node soak_feeder" >&2
    exit 1
  fi
done
[ -r "$bag" ] || { echo "soak: cannot read $bag" >&2; exit 1; }

build="$(cd "$build" && pwd)"
devel="$(cd "$devel" && pwd)"
bin="$devel/lib/lcp_contact_solver"
export ROS_HOME="$build/ros_home"
export ROS_LOG_DIR="$ROS_HOME/log"
mkdir -p "$ROS_LOG_DIR" "$(dirname "$csv")"
set +u
# shellcheck disable=SC1091
source "$devel/setup.bash"
set -u
# A master of our own on a free port: never meets a test's or the user's.
port="$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')"
export ROS_MASTER_URI="http://localhost:$port"

# Each process in its own session (setsid), so a stop reaches roscore's children too.
roscore_pid="" node_pid="" feeder_pid=""
# shellcheck disable=SC2317  # reached from the EXIT trap
stop() {  # stop PID: SIGINT to its group, up to 5 s, then SIGKILL
  [ -n "$1" ] || return 0
  kill -INT -- "-$1" 2>/dev/null || return 0
  for _ in $(seq 50); do kill -0 "$1" 2>/dev/null || return 0; sleep 0.1; done
  kill -KILL -- "-$1" 2>/dev/null || true
}
# shellcheck disable=SC2317
cleanup() { stop "$feeder_pid"; stop "$node_pid"; stop "$roscore_pid"; }
trap cleanup EXIT
trap 'exit 130' INT TERM

setsid roscore -p "$port" >"$ROS_LOG_DIR/soak_roscore.out" 2>&1 </dev/null &
roscore_pid=$!
for _ in $(seq 100); do rosparam list >/dev/null 2>&1 && break; sleep 0.2; done
rosparam load "$here/config/default.yaml" /contact_solver || { echo "soak: no master on port $port" >&2; exit 1; }
for p in "${params[@]}"; do rosparam set "/contact_solver/${p%%=*}" "${p#*=}" || exit 1; done
node_cmd=("$bin/contact_solver_node")
[ -z "$pin" ] || node_cmd=(taskset -c "$pin" "$bin/contact_solver_node")
setsid "${node_cmd[@]}" __name:=contact_solver >"$ROS_LOG_DIR/soak_node.out" 2>&1 </dev/null &
node_pid=$!

rss() { awk '/^VmRSS:/ {print $2}' "/proc/$node_pid/status" 2>/dev/null; }
cpu_ticks() { awk '{print $14 + $15}' "/proc/$node_pid/stat" 2>/dev/null; }  # utime + stime
echo "soak: node pid $node_pid, $(basename "$bag"), ${rate} Hz for ${duration} s, ${params[*]:-default parameters}; CSV $csv" | tee "$log"
echo "soak: $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg) at the start" | tee -a "$log"
setsid "$bin/soak_feeder" "$bag" --rate "$rate" --duration "$duration" >>"$log" 2>&1 </dev/null &
feeder_pid=$!
ticks0=$(cpu_ticks)

# One sample per second on a fixed schedule (sleep to the next whole second), until the
# feeder exits; the forces count is the last one the feeder logged.
echo "time_s,rss_kib,forces_received" >"$csv"
t0=$(date +%s%N)
k=0
while kill -0 "$feeder_pid" 2>/dev/null && kill -0 "$node_pid" 2>/dev/null; do
  now=$(date +%s%N)
  forces=$(awk '$1 == "t" {f = $10} END {print f + 0}' "$log")
  r=$(rss)
  [ -n "$r" ] && printf '%.1f,%s,%s\n' "$(((now - t0) / 1000000))e-3" "$r" "$forces" >>"$csv"
  [ $((k % 30)) -eq 0 ] && [ -n "$r" ] && echo "soak: t $(((now - t0) / 1000000000)) s  RSS $r KiB  forces $forces"
  k=$((k + 1))
  wait_ns=$((t0 + k * 1000000000 - $(date +%s%N)))
  [ "$wait_ns" -gt 0 ] && sleep "$((wait_ns / 1000000))e-3"
done

status=0
if kill -0 "$node_pid" 2>/dev/null; then
  wait "$feeder_pid" || status=$?
  feeder_pid=""
  # How busy the node was: near 100 % of a core means the rate asked is at its limit here.
  awk -v c0="$ticks0" -v c1="$(cpu_ticks)" -v hz="$(getconf CLK_TCK)" -v s="$((($(date +%s%N) - t0) / 1000000))e-3" \
    'BEGIN {printf "soak: node CPU %.1f s in %.1f s (%.0f %% of one core)\n", (c1 - c0) / hz, s, 100 * (c1 - c0) / hz / s}' |
    tee -a "$log"
else
  echo "soak: the node died during the run (see $ROS_LOG_DIR/soak_node.out)" | tee -a "$log" >&2
  status=1
fi
echo "soak: load average $(cut -d' ' -f1-3 /proc/loadavg) at the end" | tee -a "$log"
grep -E '^(soak_feeder|summary|failures|latency)' "$log"
awk -F, -v half="$(awk "BEGIN {print $duration / 2}")" '
  NR == 1 { next }
  { t = $1; r = $2; if (r > max) max = r; last_t = t; last = r
    if (at10 == "" && (t >= 10 || t >= half)) { at10 = r; t10 = t }  # short runs: at half time
    if (t >= half) { n++; sx += t; sy += r; sxx += t * t; sxy += t * r } }
  END {
    if (n < 2) { print "soak: too few RSS samples for a summary"; exit }
    slope = n > 1 && n * sxx - sx * sx > 0 ? (n * sxy - sx * sy) / (n * sxx - sx * sx) * 60 : 0
    printf "soak: RSS %s KiB at %.0f s, %s KiB at the end (%.0f s), max %s KiB; slope over the second half %+.1f KiB/min (%d samples)\n",
      at10, t10, last, last_t, max, slope, n }' "$csv" | tee -a "$log"
exit $status
