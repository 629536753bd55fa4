// A 1 kHz controller loop: every millisecond, the RNEA Jacobian d tau / d[q, v, a] of the
// arm at the current state, through robodiff's Client (local mode when the compiled
// library is in the shared cache, else the server). Reports how long each evaluation
// took and how late each tick woke, so the jitter a controller would see is visible.
//
//   controller_loop [--urdf FILE] [--seconds S] [--rate HZ] [--server ADDR] [--cache DIR] [--realtime]
// The default robot is the Panda from ../shared when there, else the project's arm7.
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "robodiff/client/client.hpp"

namespace {

const char* kSpec =
    R"({"function": "rnea", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "a"]}]})";

struct Summary {
  double p50, p99, max;
};

Summary summarize(std::vector<double> us) {
  std::sort(us.begin(), us.end());
  if (us.empty()) return {0, 0, 0};
  return {us[us.size() / 2], us[std::min(us.size() - 1, us.size() * 99 / 100)], us.back()};
}

timespec addNanos(timespec t, long ns) {
  t.tv_nsec += ns;
  while (t.tv_nsec >= 1'000'000'000) {
    t.tv_nsec -= 1'000'000'000;
    ++t.tv_sec;
  }
  return t;
}

double microsBetween(const timespec& a, const timespec& b) {
  return (b.tv_sec - a.tv_sec) * 1e6 + (b.tv_nsec - a.tv_nsec) / 1e3;
}

}  // namespace

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  std::string urdf = std::string(ROBODIFF_SHARED_DIR) + "/robots/panda_arm_fixed_fingers.urdf";
  if (!fs::exists(urdf)) urdf = std::string(ROBODIFF_SOURCE_DIR) + "/examples/robots/arm7.urdf";
  double seconds = 10, rate = 1000;
  bool want_realtime = false;
  robodiff::client::ClientOptions options;
  for (int i = 1; i < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--realtime") {
      want_realtime = true;
      --i;
      continue;
    }
    if (i + 1 >= argc) {
      std::fprintf(stderr, "controller_loop: %s needs a value\n", a.c_str());
      return 2;
    }
    if (a == "--urdf") urdf = argv[i + 1];
    else if (a == "--seconds") seconds = std::atof(argv[i + 1]);
    else if (a == "--rate") rate = std::atof(argv[i + 1]);
    else if (a == "--server") options.server = robodiff::client::parseServerAddress(argv[i + 1]);
    else if (a == "--cache") options.cache_dir = argv[i + 1];
    else {
      std::fprintf(stderr, "usage: controller_loop [--urdf FILE] [--seconds S] [--rate HZ] [--server ADDR] [--cache DIR] [--realtime]\n");
      return 2;
    }
  }
  try {
    robodiff::client::Client client(options);
    const robodiff::client::ModelInfo model = client.loadModelFile(urdf);
    const robodiff::client::Function rnea_jacobian = client.function(model, kSpec);
    const int nv = model.nv;
    std::vector<double> in(rnea_jacobian.inputCount()), out(rnea_jacobian.outputCount());

    // Wake-ups without the kernel's default 50 us of timer slack. With --realtime, what a
    // real-time controller does besides: memory locked and SCHED_FIFO (needs root or
    // CAP_SYS_NICE). Measured here (2-core VM): local mode gains (lateness p99 110 -> 61
    // us, no overruns); shm mode loses (p50 18 -> 50 us: the server and the client's
    // receive thread run at normal priority, below the controller).
    prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
    bool locked = false, realtime = false;
    if (want_realtime) {
      locked = mlockall(MCL_CURRENT | MCL_FUTURE) == 0;
      sched_param fifo{};
      fifo.sched_priority = 80;
      realtime = sched_setscheduler(0, SCHED_FIFO, &fifo) == 0;
    }

    const long period_ns = static_cast<long>(1e9 / rate);
    const long ticks = static_cast<long>(seconds * rate);
    std::vector<double> eval_us, late_us;
    eval_us.reserve(ticks);
    late_us.reserve(ticks);
    long failures = 0, overruns = 0;
    timespec next;
    clock_gettime(CLOCK_MONOTONIC, &next);
    for (long k = 0; k < ticks; ++k) {
      next = addNanos(next, period_ns);
      clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
      timespec woke, done;
      clock_gettime(CLOCK_MONOTONIC, &woke);
      // The state of a slow sinusoidal motion (q, v, a of every joint).
      const double t = k / rate;
      for (int j = 0; j < nv; ++j) {
        const double w = 0.5 + 0.1 * j;
        in[j] = 0.4 * std::sin(w * t);
        in[nv + j] = 0.4 * w * std::cos(w * t);
        in[2 * nv + j] = -0.4 * w * w * std::sin(w * t);
      }
      const robodiff::Status s = rnea_jacobian.evaluate(in, out);
      clock_gettime(CLOCK_MONOTONIC, &done);
      if (!s.ok()) ++failures;
      eval_us.push_back(microsBetween(woke, done));
      late_us.push_back(microsBetween(next, woke));
      if (microsBetween(next, done) * 1e3 > period_ns) ++overruns;
    }
    const Summary e = summarize(eval_us), l = summarize(late_us);
    std::printf("controller_loop: %s, %ld ticks at %.0f Hz, RNEA Jacobian (%zu outputs) via %s\n", urdf.c_str(), ticks,
                rate, out.size(), robodiff::client::toString(rnea_jacobian.mode()));
    std::printf("  evaluate:  p50 %.2f us  p99 %.2f us  max %.2f us\n", e.p50, e.p99, e.max);
    std::printf("  wake-up lateness (jitter): p50 %.1f us  p99 %.1f us  max %.1f us\n", l.p50, l.p99, l.max);
    std::printf("  failed calls %ld, ticks that overran the period %ld\n", failures, overruns);
    std::printf("  scheduler: %s, memory %s\n",
                realtime ? "SCHED_FIFO 80" : (want_realtime ? "normal (SCHED_FIFO not permitted)" : "normal"),
                locked ? "locked" : "not locked");
    return failures == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "controller_loop: %s\n", e.what());
    return 1;
  }
}
