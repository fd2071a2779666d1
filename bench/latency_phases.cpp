// The measurement loop of the latency benchmark: one phase of pairs sent to the live solver
// (one in flight, N in flight, or on a fixed clock), then drained and reported.
#include "latency_live.h"

#include <chrono>
#include <cmath>
#include <mutex>
#include <string>
#include <thread>

namespace lcs_bench::latency {

void runPhase(const PhaseContext& ctx, const std::string& name, int inflight, int count, double seconds,
              double pace_hz) {
  const Options& o = ctx.o;
  Tracker& tracker = ctx.tracker;
  tracker.reset();
  const double cpu0 = o.solver_pid > 0 ? cpuSeconds(o.solver_pid) : std::nan("");
  const auto t0 = Clock::now();
  long sent = 0, lost = 0, skipped = 0, ticks = 0;
  std::unique_lock<std::mutex> lock(tracker.m);
  for (;;) {
    const double elapsed = secondsSince(t0);
    if (count > 0 ? (sent >= count || (elapsed >= o.latency_seconds && sent >= 10)) : elapsed >= seconds)
      break;
    if (!ros::ok()) break;
    if (pace_hz > 0.0) {
      const auto next =
          t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(ticks / pace_hz));
      if (Clock::now() < next) {
        lock.unlock();
        std::this_thread::sleep_until(next);
        lock.lock();
        continue;
      }
      ++ticks;
      lost += tracker.expire(5.0);
      if (tracker.in_flight >= inflight) {
        ++skipped;
        continue;
      }
    } else if (tracker.in_flight >= inflight) {
      tracker.cv.wait_for(lock, std::chrono::milliseconds(50));
      lost += tracker.expire(5.0);
      continue;
    }
    lock.unlock();
    ctx.sender.send(ctx.p);
    ++sent;
    lock.lock();
  }
  const double elapsed = secondsSince(t0);
  // Drain: the last answers are on their way.
  const auto drain = Clock::now();
  while (tracker.in_flight > 0 && secondsSince(drain) < 5.0)
    tracker.cv.wait_for(lock, std::chrono::milliseconds(50));
  lost += tracker.expire(0.0);
  const double cpu1 = o.solver_pid > 0 ? cpuSeconds(o.solver_pid) : std::nan("");
  PhaseCounts c;
  c.sent = sent;
  c.lost = lost;
  c.skipped = skipped;
  c.elapsed = elapsed;
  c.wall = secondsSince(t0);
  c.cpu0 = cpu0;
  c.cpu1 = cpu1;
  reportPhase(ctx, name, inflight, pace_hz, c);  // still under the lock: no late answer changes the figures
}

}  // namespace lcs_bench::latency
