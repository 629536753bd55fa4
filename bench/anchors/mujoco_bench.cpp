// mujoco_bench: the MuJoCo side of bench/anchors' semi-implicit Euler step rows. Loads
// the binary model mujoco_model.py wrote (one motor per joint, Euler at dt = 0.01,
// contacts and constraints off), and on one preallocated mjData times, the way
// `robodiff bench` times its own (bench_timing.hpp):
//   euler_step_value             the state set, then mj_step (MuJoCo's step: mj_forward,
//                                then the Euler update v += dt qacc, q = integrate(q, dt v));
//   euler_step_jacobian          the state set, mjd_transitionFD forward differences
//                                (A = d x_next / d x, B = d x_next / d u), then mj_step;
//   euler_step_jacobian_centered the same with centered differences.
// It writes the outputs at every state of the states file (MuJoCo's order; compare.py
// maps them to Pinocchio's and checks them) and the figures as JSON.
//
//   mujoco_bench --model FILE.mjb --states FILE --out FILE [--quick] [--eps 1e-6]
//
// The states file: a line "count nq nv nu", then one line per state: qpos, qvel, ctrl.
// The first state is the one timed.
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "arg_reader.hpp"
#include "commands/bench_timing.hpp"

namespace {

using robodiff::cli::bench::doNotOptimize;
using robodiff::cli::bench::secondsPerCall;
using robodiff::cli::bench::TimingPlan;

struct Args {
  std::string model, states, out;
  bool quick = false;
  double eps = 1e-6;
};

Args parseArgs(int argc, char** argv) {
  Args a;
  for (anchors::ArgReader args(argc, argv); args.next();) {
    const std::string k = args.option();
    if (k == "--model") a.model = args.value();
    else if (k == "--states") a.states = args.value();
    else if (k == "--out") a.out = args.value();
    else if (k == "--quick") a.quick = true;
    else if (k == "--eps") a.eps = std::stod(args.value());
    else throw std::runtime_error("unknown option " + k);
  }
  if (a.model.empty() || a.states.empty() || a.out.empty())
    throw std::runtime_error("--model, --states and --out are required");
  if (!(a.eps > 0)) throw std::runtime_error("--eps must be positive");
  return a;
}

struct StepState {
  std::vector<mjtNum> qpos, qvel, ctrl;
};

std::vector<StepState> readStates(const std::string& path, const mjModel& m) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  int count = 0, nq = 0, nv = 0, nu = 0;
  if (!(in >> count >> nq >> nv >> nu)) throw std::runtime_error(path + ": no header line \"count nq nv nu\"");
  if (nq != m.nq || nv != m.nv || nu != m.nu)
    throw std::runtime_error(path + ": sizes " + std::to_string(nq) + " " + std::to_string(nv) + " " +
                             std::to_string(nu) + " are not the model's " + std::to_string(m.nq) + " " +
                             std::to_string(m.nv) + " " + std::to_string(m.nu));
  if (count < 1) throw std::runtime_error(path + ": no state");
  std::vector<StepState> states(count);
  auto read = [&](std::vector<mjtNum>& x, int n) {
    x.resize(n);
    for (mjtNum& v : x)
      if (!(in >> v)) throw std::runtime_error(path + ": too few numbers for " + std::to_string(count) + " states");
  };
  for (StepState& s : states) read(s.qpos, nq), read(s.qvel, nv), read(s.ctrl, nu);
  return states;
}

// The model and one preallocated mjData, and the transition matrices' buffers.
struct MujocoStep {
  mjModel* m;
  mjData* d;
  std::vector<mjtNum> A, B;  // row-major (2nv x 2nv), (2nv x nu)

  explicit MujocoStep(mjModel* model)
      : m(model), d(mj_makeData(model)), A(4 * model->nv * model->nv), B(2 * model->nv * model->nu) {
    if (!d) throw std::runtime_error("mj_makeData failed");
  }
  ~MujocoStep() { mj_deleteData(d), mj_deleteModel(m); }
  MujocoStep(const MujocoStep&) = delete;
  MujocoStep& operator=(const MujocoStep&) = delete;

  void set(const StepState& s) {
    mju_copy(d->qpos, s.qpos.data(), static_cast<int>(m->nq));
    mju_copy(d->qvel, s.qvel.data(), static_cast<int>(m->nv));
    mju_copy(d->ctrl, s.ctrl.data(), static_cast<int>(m->nu));
    d->time = 0;
  }
  void step(const StepState& s) {
    set(s);
    mj_step(m, d);
    doNotOptimize(d->qpos[0]);
  }
  void stepWithJacobian(const StepState& s, double eps, bool centered) {
    set(s);
    mjd_transitionFD(m, d, eps, centered ? 1 : 0, A.data(), B.data(), nullptr, nullptr);
    mj_step(m, d);
    doNotOptimize(A[0]);
  }
};

// ---- JSON (numbers with 17 significant digits) ----

std::string number(double x) {
  if (!std::isfinite(x)) return "null";
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", x);
  return b;
}
std::string array(const mjtNum* x, int n) {
  std::string o = "[";
  for (int i = 0; i < n; ++i) o += (i ? "," : "") + number(x[i]);
  return o + "]";
}
// [A B] as rows of 2nv + nu numbers.
std::string transitionJson(const MujocoStep& s) {
  const int nx = static_cast<int>(2 * s.m->nv), nu = static_cast<int>(s.m->nu);
  std::string o = "[";
  for (int r = 0; r < nx; ++r) {
    std::vector<mjtNum> row(s.A.begin() + r * nx, s.A.begin() + (r + 1) * nx);
    row.insert(row.end(), s.B.begin() + r * nu, s.B.begin() + (r + 1) * nu);
    o += (r ? "," : "") + array(row.data(), static_cast<int>(row.size()));
  }
  return o + "]";
}

// One state's outputs: the next state [qpos; qvel] and [A B], forward and centered.
std::string outputsJson(MujocoStep& s, const StepState& state, double eps) {
  s.stepWithJacobian(state, eps, false);
  std::vector<mjtNum> next(s.d->qpos, s.d->qpos + s.m->nq);
  next.insert(next.end(), s.d->qvel, s.d->qvel + s.m->nv);
  std::string o = "{\"value\":" + array(next.data(), static_cast<int>(next.size())) +
                  ",\"forward\":" + transitionJson(s);
  s.stepWithJacobian(state, eps, true);
  return o + ",\"centered\":" + transitionJson(s) + "}";
}

int run(const Args& a) {
  mjModel* model = mj_loadModel(a.model.c_str(), nullptr);
  if (!model) throw std::runtime_error("MuJoCo could not load " + a.model);
  MujocoStep s(model);
  if (model->opt.integrator != mjINT_EULER || model->nu != model->nv)
    throw std::runtime_error(a.model + ": not a model of mujoco_model.py (Euler integrator, one motor per joint)");
  const std::vector<StepState> states = readStates(a.states, *model);
  const TimingPlan plan = a.quick ? TimingPlan::quick() : TimingPlan::full();

  std::fprintf(stderr, "mujoco_bench: MuJoCo %s (nq %ld, nv %ld, nu %ld) ...\n", mj_versionString(),
               static_cast<long>(model->nq), static_cast<long>(model->nv), static_cast<long>(model->nu));
  std::string outputs = "[";
  for (size_t k = 0; k < states.size(); ++k) outputs += (k ? ",\n  " : "") + outputsJson(s, states[k], a.eps);
  outputs += "]";

  const StepState& timed = states.front();
  const double value_us = 1e6 * secondsPerCall([&] { s.step(timed); }, plan);
  const double forward_us = 1e6 * secondsPerCall([&] { s.stepWithJacobian(timed, a.eps, false); }, plan);
  const double centered_us = 1e6 * secondsPerCall([&] { s.stepWithJacobian(timed, a.eps, true); }, plan);

  std::ofstream out(a.out);
  out << "{\"mujoco_version\":\"" << mj_versionString() << "\",\"nq\":" << model->nq << ",\"nv\":" << model->nv
      << ",\"nu\":" << model->nu << ",\"dt\":" << number(model->opt.timestep) << ",\"eps\":" << number(a.eps)
      << ",\n \"rows\":[{\"name\":\"euler_step_value\",\"us_per_call\":" << number(value_us)
      << "},{\"name\":\"euler_step_jacobian\",\"us_per_call\":" << number(forward_us)
      << "},{\"name\":\"euler_step_jacobian_centered\",\"us_per_call\":" << number(centered_us)
      << "}],\n \"outputs\":" << outputs << "}\n";
  if (!out) throw std::runtime_error("cannot write " + a.out);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return anchors::guardedMain("mujoco_bench", [&] { return run(parseArgs(argc, argv)); });
}
