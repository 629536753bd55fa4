// `robodiff identify` as a user runs it: a real process, samples written to a CSV file by
// the synthetic generator (a perturbed arm7 as the truth, noisy torques), the JSON read
// back and checked against the truth (base parameters within a few standard errors,
// held-out residuals near the noise), the written URDF loaded again; the compiled backend
// through a fresh cache once; bad input named by file and line; --physical on poor data
// writing a URDF whose every body is valid.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "identification_fixture.hpp"
#include "robodiff/batch/base_parameters.hpp"
#include "robodiff/batch/physical_fit.hpp"
#include "robodiff/batch/physical_validity.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::testing {
namespace {

std::string cli(const std::string& args) { return shellQuote(cliPath().string()) + " " + args; }

struct CliWorkspace {
  TempDir tmp;
  Robot robot = arm7();
  Model truth = batch::perturbInertias(robot.model, 0.3, 23);
  double sigma = 0.03;
  std::filesystem::path csv = writeSamples();

  std::filesystem::path writeSamples() {
    const batch::MeasuredSamples s = batch::syntheticSamples(truth, syntheticOptions(1000, sigma, 5));
    batch::writeMeasuredSamples(tmp / "samples.csv", s, robot.model);
    return tmp / "samples.csv";
  }
  std::string identify(const std::string& extra) const {
    return cli("identify --urdf " + shellQuote(robot.path.string()) + " --data " + shellQuote(csv.string()) +
               " --cache " + shellQuote((tmp / "cache").string()) + " " + extra);
  }
};

TEST(IdentifyCli, JsonAgreesWithTheTruthAndTheUrdfReloads) {
  CliWorkspace w;
  const std::filesystem::path out = w.tmp / "identified.urdf";
  const ProcessResult r =
      runCommand(w.identify("--holdout 0.2 --json --backend interpreted --out-urdf " + shellQuote(out.string())));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["method"], "ols");
  EXPECT_EQ(j["fit_samples"], 800);
  EXPECT_EQ(j["held_out_samples"], 200);
  // The truth's base parameters, computed here from the library, not by the process.
  const batch::BaseParameters base = batch::computeBaseParameters(w.robot.model);
  const Eigen::VectorXd truth = base.fromStandard(batch::modelParameters(w.truth));
  ASSERT_EQ(j["base_parameters"].size(), static_cast<std::size_t>(truth.size()));
  for (Eigen::Index k = 0; k < truth.size(); ++k) {
    const nlohmann::json& p = j["base_parameters"][static_cast<std::size_t>(k)];
    EXPECT_LE(std::abs(p["value"].get<double>() - truth[k]), 5 * p["std_error"].get<double>()) << p["expression"];
  }
  for (std::size_t i = 0; i < 7; ++i) {
    EXPECT_NEAR(j["residual_rms"]["held_out"][i].get<double>(), w.sigma, 0.3 * w.sigma) << i;
    EXPECT_GT(j["residual_rms"]["prior_held_out"][i].get<double>(), j["residual_rms"]["held_out"][i].get<double>());
  }
  EXPECT_EQ(j["bodies"].size(), 7u);
  EXPECT_EQ(j["bodies"][6]["merged_links"], nlohmann::json::array({"tool"}));
  ASSERT_TRUE(j["out_urdf"]["written"].get<bool>()) << j["out_urdf"].dump();
  // The written URDF holds the identified parameters.
  const Eigen::VectorXd back = batch::modelParameters(loadUrdfFile(out.string()));
  for (std::size_t b = 0; b < 7; ++b)
    for (int i = 0; i < batch::kParametersPerBody; ++i) {
      const double want = j["bodies"][b]["parameters"][batch::kParameterSymbols[i]].get<double>();
      EXPECT_NEAR(back[static_cast<Eigen::Index>(10 * b) + i], want, 1e-12 * (1 + std::abs(want)));
    }
}

TEST(IdentifyCli, CompiledWeightedTable) {
  CliWorkspace w;
  const ProcessResult r = runCommand(w.identify("--holdout 0.25 --weighted --backend compiled --threads 2"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("weighted least squares on 750 samples, 250 held out"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Base parameters"), std::string::npos);
  EXPECT_NE(r.out.find("Residual RMS per joint"), std::string::npos);
  EXPECT_NE(r.out.find("stacking the regressor"), std::string::npos);
  EXPECT_NE(r.out.find("Identified bodies"), std::string::npos);
  EXPECT_NE(r.out.find("mcx_link7"), std::string::npos);  // a base parameter on its own
  EXPECT_NE(r.err.find("building the regressor"), std::string::npos) << r.err;
}

TEST(IdentifyCli, BadCsvIsReportedWithFileLineAndColumn) {
  CliWorkspace w;
  std::string text = readFile(w.csv);
  // Line 4 (the third sample): its first field becomes text.
  std::size_t at = 0;
  for (int line = 1; line < 4; ++line) at = text.find('\n', at) + 1;
  text.replace(at, text.find(',', at) - at, "oops");
  w.csv = w.tmp.file("bad.csv", text);
  const ProcessResult r = runCommand(w.identify("--backend interpreted"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(w.csv.string() + ":4: column t: 'oops' is not a number"), std::string::npos) << r.err;
}

// Poor data (a third of a second of motion, heavy noise) to fit, then rich samples held
// out: least squares leaves invalid bodies; --physical gives valid ones, predicts the held-out
// torques better, and writes a URDF that loads with every body valid.
TEST(IdentifyCli, PhysicalWritesAValidUrdfFromPoorData) {
  CliWorkspace w;
  const batch::MeasuredSamples all = poorThenRichSamples(w.truth, 0.5, 30, 300);
  batch::writeMeasuredSamples(w.tmp / "poor.csv", all, w.robot.model);
  w.csv = w.tmp / "poor.csv";
  const std::string common = "--holdout 0.90909 --json --backend interpreted ";

  const ProcessResult ls = runCommand(w.identify(common));
  ASSERT_EQ(ls.exit_code, 0) << ls.err;
  const nlohmann::json ls_json = nlohmann::json::parse(ls.out);
  EXPECT_EQ(ls_json["held_out_samples"], 300);
  bool ls_invalid = false;
  for (const nlohmann::json& b : ls_json["bodies"]) ls_invalid |= !b["physically_consistent"].get<bool>();
  ASSERT_TRUE(ls_invalid) << "the data are not poor enough to make the point";

  const std::filesystem::path out = w.tmp / "physical.urdf";
  const ProcessResult r = runCommand(w.identify(common + "--physical --out-urdf " + shellQuote(out.string())));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["method"], "physical");
  EXPECT_EQ(j["solver"]["status"], "Solve_Succeeded");
  EXPECT_GT(j["solver"]["iterations"].get<int>(), 0);
  EXPECT_EQ(j["solver"]["regularization"].get<double>(), batch::PhysicalFitOptions{}.regularization);
  for (const nlohmann::json& b : j["bodies"]) EXPECT_TRUE(b["physically_consistent"].get<bool>()) << b.dump();
  for (std::size_t i = 0; i < 7; ++i)
    EXPECT_LT(j["residual_rms"]["held_out"][i].get<double>(), ls_json["residual_rms"]["held_out"][i].get<double>());
  ASSERT_TRUE(j["out_urdf"]["written"].get<bool>()) << j["out_urdf"].dump();
  const Model reloaded = loadUrdfFile(out.string());
  for (const batch::BodyValidity& v : batch::checkValidity(batch::modelParameters(reloaded)))
    EXPECT_TRUE(v.valid) << v.message;
}

TEST(IdentifyCli, PhysicalTableAndOptions) {
  CliWorkspace w;
  const ProcessResult r =
      runCommand(w.identify("--backend interpreted --physical --weighted --regularization 1e-6 --holdout 0.2"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("physically consistent fit (Ipopt) on 800 samples, 200 held out"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Physical validity per body"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Ipopt: Solve_Succeeded"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("regularization 1e-06, weighting per-joint noise"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("NO"), std::string::npos) << r.out;  // no invalid body
  // The regularisation belongs to --physical; a negative one is refused.
  const ProcessResult alone = runCommand(w.identify("--backend interpreted --regularization 1e-6"));
  EXPECT_NE(alone.exit_code, 0);
  EXPECT_NE(alone.err.find("--physical"), std::string::npos) << alone.err;
  const ProcessResult negative = runCommand(w.identify("--backend interpreted --physical --regularization -1"));
  EXPECT_EQ(negative.exit_code, 1);
  EXPECT_NE(negative.err.find("--regularization"), std::string::npos) << negative.err;
}

}  // namespace
}  // namespace robodiff::testing
