// anchors_bench: times Pinocchio's analytic algorithms and CppADCodeGen's and CasADi's
// generated code for one robot, the same way `robodiff bench` times its own
// (bench_timing.hpp), and the step rows (step_rows.hpp) of Pinocchio and crocoddyl (the
// generated sides tape them on a fixed base); checks CppADCodeGen's, CasADi's and crocoddyl's outputs against Pinocchio's
// at a few states (1e-9 relative), and writes everything as JSON (compare.py reads it).
//
//   anchors_bench --urdf FILE [--floating-base] --out FILE --workdir DIR
//                 [--quick] [--cap SECONDS] [--reuse] [--seed N] [--checks N]
//                 [--codegen-rows a,b,...] [--no-codegen] [--no-casadi]
//                 [--build-only | --list-rows]
// (CasADi's libraries go to WORKDIR/casadi; --codegen-rows, --cap and --reuse apply to both.)
// --build-only builds the generated sides' libraries and stops (no timing, no checks);
// --list-rows writes to --out which libraries each generated side builds for the robot.
// compare.py runs one --build-only per library, several at once, then times with --reuse.
#include <pinocchio/parsers/urdf.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

#include "anchors.hpp"
#include "arg_reader.hpp"
#include "step_rows.hpp"

namespace {

constexpr double kLimit = 1e-9;  // relative error a side may have against Pinocchio's analytic outputs

struct Args {
  std::string urdf, out, workdir;
  bool floating_base = false, quick = false, reuse = false, codegen = true, casadi = true;
  bool build_only = false, list_rows = false;
  double cap = 120;
  unsigned seed = 1;
  int checks = 3;
  std::vector<std::string> codegen_rows;
};

std::vector<std::string> splitCommas(const std::string& s) {
  std::vector<std::string> parts;
  std::stringstream in(s);
  for (std::string p; std::getline(in, p, ',');)
    if (!p.empty()) parts.push_back(p);
  return parts;
}

Args parseArgs(int argc, char** argv) {
  Args a;
  for (anchors::ArgReader args(argc, argv); args.next();) {
    const std::string k = args.option();
    if (k == "--urdf") a.urdf = args.value();
    else if (k == "--out") a.out = args.value();
    else if (k == "--workdir") a.workdir = args.value();
    else if (k == "--floating-base") a.floating_base = true;
    else if (k == "--quick") a.quick = true;
    else if (k == "--reuse") a.reuse = true;
    else if (k == "--build-only") a.build_only = true;
    else if (k == "--list-rows") a.list_rows = true;
    else if (k == "--no-codegen") a.codegen = false;
    else if (k == "--no-casadi") a.casadi = false;
    else if (k == "--cap") a.cap = std::stod(args.value());
    else if (k == "--seed") a.seed = static_cast<unsigned>(std::stoul(args.value()));
    else if (k == "--checks") a.checks = std::stoi(args.value());
    else if (k == "--codegen-rows") a.codegen_rows = splitCommas(args.value());
    else throw std::runtime_error("unknown option " + k);
  }
  if (a.urdf.empty() || a.out.empty() || a.workdir.empty())
    throw std::runtime_error("--urdf, --out and --workdir are required");
  for (const std::string& r : a.codegen_rows)
    if (std::find(anchors::kRows.begin(), anchors::kRows.end(), r) == anchors::kRows.end() &&
        std::find(anchors::kStepRows.begin(), anchors::kStepRows.end(), r) == anchors::kStepRows.end())
      throw std::runtime_error("--codegen-rows: no row " + r);
  return a;
}

// ---- JSON output (numbers with 17 significant digits) ----

std::string number(double x) {
  if (!std::isfinite(x)) return "null";
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", x);
  return b;
}
std::string quoted(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    o += c == '\n' ? ' ' : c;
  }
  return o + "\"";
}
std::string vectorJson(const Eigen::VectorXd& v) {
  std::string o = "[";
  for (Eigen::Index i = 0; i < v.size(); ++i) o += (i ? "," : "") + number(v[i]);
  return o + "]";
}
std::string matrixJson(const Eigen::MatrixXd& m) {
  std::string o = "[";
  for (Eigen::Index r = 0; r < m.rows(); ++r) o += (r ? "," : "") + vectorJson(m.row(r).transpose());
  return o + "]";
}
std::string optionalJson(const std::optional<double>& x) { return x ? number(*x) : "null"; }

// The step + cost rows' extra outputs, when there are any.
std::string stepOutputsJson(const anchors::Output& o) {
  std::string s;
  if (o.gradient.size()) s += ",\"gradient\":" + vectorJson(o.gradient);
  if (o.hessian.size()) s += ",\"hessian\":" + matrixJson(o.hessian);
  if (o.exact_hessian.size()) s += ",\"exact_hessian\":" + matrixJson(o.exact_hessian);
  return s;
}

std::string rowJson(const anchors::RowResult& r, bool with_outputs) {
  std::string o = "{\"name\":" + quoted(r.name) + ",\"us_per_call\":" + optionalJson(r.us) +
                  ",\"build_seconds\":" + optionalJson(r.build_s) + ",\"compiler_mib\":" + optionalJson(r.compiler_mib) +
                  ",\"status\":" + quoted(r.status) + ",\"note\":" + quoted(r.note) + ",\"max_err\":" + number(r.max_err);
  if (with_outputs) {
    o += ",\"outputs\":[";
    for (size_t k = 0; k < r.outputs.size(); ++k)
      o += std::string(k ? "," : "") + "{\"value\":" + vectorJson(r.outputs[k].value) +
           ",\"jacobian\":" + matrixJson(r.outputs[k].jacobian) + stepOutputsJson(r.outputs[k]) + "}";
    o += "]";
  }
  return o + "}";
}

std::string sideJson(const std::vector<anchors::RowResult>& rows, bool with_outputs) {
  std::string o = "[";
  for (size_t k = 0; k < rows.size(); ++k) o += (k ? ",\n    " : "") + rowJson(rows[k], with_outputs);
  return o + "]";
}

// Checks `side` against Pinocchio's outputs (the row of the same name); a row that
// disagrees loses its figure. Hessians: Gauss-Newton against Gauss-Newton.
void checkAgainst(const std::vector<anchors::RowResult>& reference, std::vector<anchors::RowResult>& side) {
  for (anchors::RowResult& r : side) {
    if (r.status != "ok") continue;
    const auto ref = std::find_if(reference.begin(), reference.end(), [&](const auto& x) { return x.name == r.name; });
    if (ref == reference.end()) throw std::logic_error("no Pinocchio row " + r.name);
    double err = 0;
    for (size_t k = 0; k < r.outputs.size(); ++k) {
      const anchors::Output &o = r.outputs[k], &e = ref->outputs[k];
      for (auto [a, b] : {std::pair{&o.value, &e.value}, std::pair{&o.gradient, &e.gradient}})
        err = std::max(err, anchors::relativeError(*a, *b));
      for (auto [a, b] : {std::pair{&o.jacobian, &e.jacobian}, std::pair{&o.hessian, &e.hessian}})
        err = std::max(err, anchors::relativeError(*a, *b));
    }
    r.max_err = err;
    if (!(err <= kLimit)) {
      char b[80];
      std::snprintf(b, sizeof b, "WRONG: max err %.3g", err);
      r.status = "wrong", r.note = b, r.us.reset();
    }
  }
}

// The generated-code anchors tape the step where q_next's coordinates are its tangent.
bool generatedStepRows(const Args& a, const pinocchio::Model& model) {
  return !a.floating_base && model.nq == model.nv;
}

// A generated side's options: its libraries in `workdir`, the cap, reuse and rows asked for.
anchors::CodegenOptions codegenOptions(const Args& a, const pinocchio::Model& model, const std::string& workdir) {
  anchors::CodegenOptions options{workdir, a.cap, a.reuse, a.codegen_rows};
  options.step_rows = generatedStepRows(a, model);
  return options;
}

std::string namesJson(const std::vector<std::string>& names) {
  std::string o = "[";
  for (size_t k = 0; k < names.size(); ++k) o += (k ? "," : "") + quoted(names[k]);
  return o + "]";
}

void writeText(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + path);
}

// --list-rows: {"cppadcodegen": [rows], "casadi": [rows], "frame": name, "nv": nv}.
int listRows(const Args& a, const pinocchio::Model& model) {
  const bool steps = generatedStepRows(a, model);
  writeText(a.out, "{\"cppadcodegen\":" + namesJson(anchors::codegenRowNames(steps)) +
                       ",\"casadi\":" + namesJson(anchors::casadiRowNames(steps)) +
                       ",\"frame\":" + quoted(model.frames[anchors::lastFrame(model)].name) +
                       ",\"nv\":" + std::to_string(model.nv) + "}\n");
  return 0;
}

// --build-only: the generated sides' libraries built (kept with --reuse), their build
// outcomes written to --out; nothing timed or checked.
int buildOnly(const Args& a, const pinocchio::Model& model, const anchors::State& timed) {
  const anchors::Timing unused_plan = anchors::Timing::quick();
  std::vector<anchors::RowResult> cg, cas;
  anchors::CodegenOptions options = codegenOptions(a, model, a.workdir);
  options.build_only = true;
  if (a.codegen) cg = anchors::runCppADCodeGen(model, timed, {}, unused_plan, options);
  options.workdir = a.workdir + "/casadi";
  if (a.casadi) cas = anchors::runCasadi(model, timed, {}, unused_plan, options);
  writeText(a.out, "{\"sides\":{\"cppadcodegen\":" + sideJson(cg, false) + ",\n  \"casadi\":" +
                       sideJson(cas, false) + "}}\n");
  return 0;
}

int run(const Args& a) {
  pinocchio::Model model;
  if (a.floating_base) pinocchio::urdf::buildModel(a.urdf, pinocchio::JointModelFreeFlyer(), model);
  else pinocchio::urdf::buildModel(a.urdf, model);
  if (a.list_rows) return listRows(a, model);
  const anchors::Timing plan = a.quick ? anchors::Timing::quick() : anchors::Timing::full();
  const std::vector<anchors::State> states = anchors::drawStates(model, a.seed, 1 + a.checks);
  const anchors::State& timed = states.front();
  if (a.build_only) return buildOnly(a, model, timed);
  const std::vector<anchors::State> checks(states.begin() + 1, states.end());

  std::fprintf(stderr, "anchors_bench: %s (nq %d, nv %d): Pinocchio ...\n", model.name.c_str(), model.nq, model.nv);
  std::vector<anchors::RowResult> pin = anchors::runPinocchio(model, timed, checks, plan);
  std::vector<anchors::RowResult> croc;
  {  // the step rows, on any base (a free-flyer's q_next and its tangent as Pinocchio's integrate)
    std::fprintf(stderr, "anchors_bench: %s: the Euler step and cost, Pinocchio and crocoddyl ...\n", model.name.c_str());
    const std::vector<anchors::RowResult> steps = anchors::runPinocchioStep(model, timed, checks, plan);
    pin.insert(pin.end(), steps.begin(), steps.end());
    croc = anchors::runCrocoddyl(model, timed, checks, plan);
    checkAgainst(pin, croc);
  }
  std::vector<anchors::RowResult> cg;
  if (a.codegen) {
    cg = anchors::runCppADCodeGen(model, timed, checks, plan, codegenOptions(a, model, a.workdir));
    checkAgainst(pin, cg);
  }
  std::vector<anchors::RowResult> cas;
  if (a.casadi) {
    cas = anchors::runCasadi(model, timed, checks, plan, codegenOptions(a, model, a.workdir + "/casadi"));
    checkAgainst(pin, cas);
  }

  std::ofstream out(a.out);
  out << "{\"robot\":" << quoted(model.name) << ",\"urdf\":" << quoted(a.urdf)
      << ",\"floating_base\":" << (a.floating_base ? "true" : "false") << ",\"nq\":" << model.nq
      << ",\"nv\":" << model.nv << ",\"frame\":" << quoted(model.frames[anchors::lastFrame(model)].name)
      << ",\"timing\":" << quoted(std::string("median of ") + std::to_string(plan.batches) + " batches of ~" +
                                  number(plan.batch_seconds * 1e3) + " ms, thread CPU time (robodiff bench's)")
      << ",\n \"states\":[";
  for (size_t k = 0; k < checks.size(); ++k)
    out << (k ? "," : "") << "{\"q\":" << vectorJson(checks[k].q) << ",\"v\":" << vectorJson(checks[k].v)
        << ",\"a\":" << vectorJson(checks[k].a) << ",\"tau\":" << vectorJson(checks[k].tau) << "}";
  out << "],\n \"sides\":{\"pinocchio\":" << sideJson(pin, true) << ",\n  \"cppadcodegen\":" << sideJson(cg, false)
      << ",\n  \"casadi\":" << sideJson(cas, false) << ",\n  \"crocoddyl\":" << sideJson(croc, false)
      << "},\n \"casadi_version\":" << quoted(anchors::casadiVersion()) << "}\n";
  if (!out) throw std::runtime_error("cannot write " + a.out);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return anchors::guardedMain("anchors_bench", [&] { return run(parseArgs(argc, argv)); });
}
