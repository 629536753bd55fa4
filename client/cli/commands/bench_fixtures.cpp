#include "commands/bench_fixtures.hpp"

#include <stdlib.h>
#include <sys/resource.h>

#include <cctype>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iterator>
#include <thread>

#include <nlohmann/json.hpp>

#include "robodiff/functions/reference.hpp"

namespace robodiff::cli::bench {

namespace fs = std::filesystem;

WorkDir::WorkDir(const std::string& keep) {
  if (!keep.empty()) {
    path_ = keep;
    fs::create_directories(path_);
    return;
  }
  std::string pattern = (fs::temp_directory_path() / "robodiff-bench-XXXXXX").string();
  if (!::mkdtemp(pattern.data())) throw std::runtime_error("cannot create a temporary directory " + pattern);
  path_ = pattern;
  remove_ = true;
}

WorkDir::~WorkDir() {
  std::error_code ec;
  if (remove_) fs::remove_all(path_, ec);
}

namespace {

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

Target atMost(double limit, const std::string& unit) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "<= %g %s", limit, unit.c_str());
  return {limit, "", buf};
}

}  // namespace

// ../shared/notes/anchors.md: Pinocchio 3.7, CppAD(CodeGen) on a 2-core Rocket Lake.
std::optional<Anchors> anchorsFor(const Model& model) {
  if (model.root != RootJoint::Fixed) return std::nullopt;
  const std::string name = lower(model.name);
  Anchors a;
  if (name.find("panda") != std::string::npos && model.nv == 7) {
    a.text = {{"rnea_double", "Pinocchio RNEA 0.80"},
              {"aba_double", "Pinocchio ABA 1.57-1.66"},
              {"rnea_value", "CppADCodeGen 0.163"},
              {"rnea_jacobian_dense", "CppADCodeGen 1.79; Pinocchio derivatives 2.90; CppAD tape 31.3"},
              {"aba_value", "CppADCodeGen 0.42"},
              {"aba_jacobian", "Pinocchio derivatives 4.32; CppADCodeGen 8.96"},
              {"rnea_fd", "central FD 36.7"},
              {"build.rnea_jacobian_dense.total", "CppADCodeGen 2.3 s -O3 compile, 116 MB, 155 KB C"},
              {"build.aba_jacobian.total", "CppADCodeGen 33.5 s -O3 compile, 715 MB, 647 KB C"}};
    a.targets = {{"rnea_value", atMost(0.163, "µs")},
                 {"rnea_jacobian_dense", atMost(0.9, "µs")},
                 {"aba_jacobian", atMost(2.2, "µs")},
                 {"build.rnea_jacobian_dense.total", atMost(1, "s")},
                 {"build.aba_jacobian.total", atMost(3, "s")}};
    return a;
  }
  if (name.find("talos") != std::string::npos && model.nv == 32) {
    a.text = {{"rnea_double", "Pinocchio RNEA 3.89"},
              {"aba_double", "Pinocchio ABA 7.5-7.9"},
              {"rnea_value", "CppADCodeGen 0.666"},
              {"rnea_jacobian_dense", "CppADCodeGen 9.32; Pinocchio derivatives 15.0; CppAD tape 520"},
              {"aba_jacobian", "Pinocchio derivatives 22.6; CppADCodeGen 391-497"},
              {"rnea_fd", "central FD 750"},
              {"build.rnea_jacobian_dense.total", "CppADCodeGen 29 s -O3 compile, 538 MB, 735 KB C"},
              {"build.aba_jacobian.total", "CppADCodeGen 96 s -O3 compile, 1.9 GB, 6.6 MB C"}};
    a.targets = {{"rnea_jacobian_dense", atMost(4.7, "µs")},
                 {"aba_jacobian", atMost(11, "µs")},
                 {"build.rnea_jacobian_dense.total", atMost(10, "s")},
                 {"build.aba_jacobian.total", atMost(30, "s")}};
    return a;
  }
  if (name.find("ur5") != std::string::npos && model.nv == 6) {
    a.text = {{"rnea_double", "Pinocchio RNEA 0.69"},
              {"rnea_jacobian_dense", "Pinocchio derivatives 2.50-2.58; CppAD tape 14.8"},
              {"rnea_fd", "central FD 27.1"}};
    return a;
  }
  return std::nullopt;
}

std::string cpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) {
      const std::size_t colon = line.find(':');
      if (colon != std::string::npos) {
        std::size_t b = line.find_first_not_of(" \t", colon + 1);
        return b == std::string::npos ? "" : line.substr(b);
      }
    }
  return "unknown CPU";
}

unsigned hardwareThreads() { return std::max(1u, std::thread::hardware_concurrency()); }

std::uint64_t processPeakBytes() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<std::uint64_t>(u.ru_maxrss) * 1024;  // Linux: KiB
}

std::string today() {
  std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%d", std::gmtime(&t));
  return buf;
}

const std::vector<SpecText> kSpecs = {
    {"rnea_value", "RNEA value", R"({"function": "rnea", "outputs": [{"kind": "value"}]})"},
    {"rnea_jacobian_dense", "RNEA + Jacobian [q,v,a], dense",
     R"({"function": "rnea", "outputs": [{"kind": "value"},
        {"kind": "jacobian", "wrt": ["q", "v", "a"], "layout": "dense"}]})"},
    {"rnea_jacobian_sparse", "RNEA + Jacobian [q,v,a], sparse",
     R"({"function": "rnea", "outputs": [{"kind": "value"},
        {"kind": "jacobian", "wrt": ["q", "v", "a"], "layout": "sparse"}]})"},
    {"aba_value", "ABA value", R"({"function": "aba", "outputs": [{"kind": "value"}]})"},
    {"aba_jacobian", "ABA + Jacobian [q,v,tau]",
     R"({"function": "aba", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "tau"]}]})"},
};

std::string withBuild(const char* json) {
  // Every spec: all inputs variable (the default), O2 and -march=native.
  std::string s = json;
  s.insert(s.size() - 1, R"(, "build": {"optimization": "O2", "march_native": true})");
  return s;
}

std::vector<BenchSpec> builtinBenchSpecs() {
  std::vector<BenchSpec> specs;
  for (const SpecText& s : kSpecs) specs.push_back({s.name, s.label, withBuild(s.json), std::string("bench:") + s.name});
  return specs;
}

namespace user_spec_detail {

// The file's stem with every character outside [A-Za-z0-9_] made '_' (a C name).
std::string identifierFromStem(const fs::path& path) {
  std::string s = path.stem().string();
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
  if (s.empty() || std::isdigit(static_cast<unsigned char>(s[0]))) s = "spec_" + s;
  return s;
}

std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument("--spec " + path + ": cannot read the file");
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// The spec with only its "value" outputs (empty when it has none, or nothing else).
std::optional<nlohmann::ordered_json> valueOutputsOnly(const nlohmann::ordered_json& spec) {
  nlohmann::ordered_json values = nlohmann::ordered_json::array();
  for (const nlohmann::ordered_json& o : spec.at("outputs"))
    if (o.value("kind", "") == "value") values.push_back(o);
  if (values.empty() || values.size() == spec.at("outputs").size()) return std::nullopt;
  nlohmann::ordered_json v = spec;
  v["outputs"] = values;
  return v;
}

}  // namespace user_spec_detail

std::vector<BenchSpec> userBenchSpecs(const std::vector<std::string>& paths, std::vector<std::string> taken) {
  using namespace user_spec_detail;
  std::vector<BenchSpec> specs;
  auto add = [&](const std::string& path, BenchSpec s) {
    if (std::find(taken.begin(), taken.end(), s.name) != taken.end())
      throw std::invalid_argument("--spec " + path + ": the row name '" + s.name +
                                  "' is taken by another row (give the spec another \"name\")");
    taken.push_back(s.name);
    specs.push_back(std::move(s));
  };
  for (const std::string& path : paths) {
    const FunctionSpec parsed = loadFunctionSpec(path);  // a bad spec fails here, naming the file and field
    // Keys in the order written: a user function's inputs are its blocks, in that order.
    const nlohmann::ordered_json spec = nlohmann::ordered_json::parse(readText(path));
    const std::string name = parsed.isUser() && spec.contains("name") ? parsed.functionName() : identifierFromStem(path);
    const std::optional<nlohmann::ordered_json> values = valueOutputsOnly(spec);
    add(path, {name, name + (values ? " (values + derivatives)" : ""), spec.dump(), path});
    if (!values) continue;
    nlohmann::ordered_json v = *values;
    if (parsed.isUser()) v["name"] = name + "_value";
    add(path, {name + "_value", name + " (values only)", v.dump(), path + " (its value outputs)"});
  }
  return specs;
}

Buffers::Buffers(const Model& model, const Generated& g, std::uint64_t knots, std::size_t work_size)
    : work(work_size) {
  const codegen::FunctionDefinition& def = g.lib.built.definition;
  for (const codegen::InputBlock& b : def.inputs) in.emplace_back(knots * b.size), in_size.push_back(b.size);
  for (const codegen::OutputBlock& b : def.outputs) out.emplace_back(knots * b.size()), out_size.push_back(b.size());
  for (std::uint64_t k = 0; k < knots; ++k) {
    const std::vector<Eigen::VectorXd> x = randomRuntimeInputs(model, g.spec, kSeed + k);
    if (x.size() != in.size()) throw std::logic_error("bench: input blocks of " + g.name + " differ from the spec");
    for (std::size_t b = 0; b < x.size(); ++b)
      std::copy(x[b].data(), x[b].data() + x[b].size(), &in[b][k * in_size[b]]);
  }
  for (auto& v : in) in_ptr.push_back(v.data());
  for (auto& v : out) out_ptr.push_back(v.data());
}

Eigen::VectorXd Buffers::input(std::size_t block, std::uint64_t knot) const {
  return Eigen::Map<const Eigen::VectorXd>(&in[block][knot * in_size[block]], in_size[block]);
}

Eigen::VectorXd Buffers::output(std::size_t block, std::uint64_t knot) const {
  return Eigen::Map<const Eigen::VectorXd>(&out[block][knot * out_size[block]], out_size[block]);
}

RneaFiniteDifferences::RneaFiniteDifferences(const Model& model, Eigen::VectorXd q, Eigen::VectorXd v,
                                             Eigen::VectorXd a)
    : model_(model),
      data_(model),
      q_(std::move(q)),
      v_(std::move(v)),
      a_(std::move(a)),
      plus_(model.nv),
      dq_(Eigen::VectorXd::Zero(model.nv)),
      J_(model.nv, 3 * model.nv) {}

void RneaFiniteDifferences::operator()() {
  const int nv = model_.nv;
  const double h = kFiniteDifferenceStep, s = 0.5 / h;
  for (int j = 0; j < nv; ++j) {
    if (model_.root == RootJoint::Fixed) {  // every joint 1-dof with idx_q = idx_v: q[j] +- h
      column(q_, j, j);
    } else {
      dq_[j] = h;
      plus_ = rnea(model_, data_, integrate(model_, q_, dq_), v_, a_);
      dq_[j] = -h;
      const auto& minus = rnea(model_, data_, integrate(model_, q_, dq_), v_, a_);
      J_.col(j) = (plus_ - minus) * s;
      dq_[j] = 0;
    }
  }
  for (int j = 0; j < nv; ++j) column(v_, j, nv + j);
  for (int j = 0; j < nv; ++j) column(a_, j, 2 * nv + j);
}

void RneaFiniteDifferences::column(Eigen::VectorXd& x, int i, int col) {
  const double x0 = x[i], h = kFiniteDifferenceStep;
  x[i] = x0 + h;
  plus_ = rnea(model_, data_, q_, v_, a_);
  x[i] = x0 - h;
  const auto& minus = rnea(model_, data_, q_, v_, a_);
  J_.col(col) = (plus_ - minus) * (0.5 / h);
  x[i] = x0;
}

static double maxAbs(const Eigen::MatrixXd& m) { return m.size() ? m.cwiseAbs().maxCoeff() : 0.0; }
double relativeError(const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected) {
  return maxAbs(actual - expected) / std::max(1.0, maxAbs(expected));
}

Row makeRow(std::string name, std::string label, std::string short_label, Unit unit, double value,
            std::vector<Ratio> ratios) {
  Row r;
  r.name = std::move(name);
  r.label = std::move(label);
  r.short_label = std::move(short_label);
  r.unit = unit;
  r.value = value;
  r.ratios = std::move(ratios);
  return r;
}

}  // namespace robodiff::cli::bench
