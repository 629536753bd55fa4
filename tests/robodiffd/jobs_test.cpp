// Batch jobs through a real robodiffd: SubmitJob, JobStatus, CancelJob and JobResult over
// iceoryx and DDS, jobs run by real robodiff-worker processes, results in the server's
// real cache (files published atomically, rows in its SQLite index). Checked: a
// trajectory job's every output against core/dynamics; a cancelled job stops within a
// second and leaves no files; a worker killed mid-job fails the job with the signal
// named; bad parameters are refused at submission naming the field; a job outlives its
// server in the index, and a job a crashed server left running is failed by the next.
#include <dirent.h>
#include <signal.h>
#include <sys/wait.h>

#include <fstream>
#include <random>
#include <thread>

#include <nlohmann/json.hpp>

#include "robodiff/batch/measured_samples.hpp"
#include "robodiff/batch/physical_validity.hpp"
#include "robodiff/batch/synthetic_samples.hpp"
#include "robodiff/batch/trajectory_output.hpp"
#include "robodiff/cache/job_index.hpp"
#include "robodiffd/service_fixture.hpp"
#include "support/process.hpp"
#include "workers/worker_fixtures.hpp"

namespace robodiff::testing {
namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;
using std::chrono::seconds;

const char* kRneaValueSpec = R"({"function": "rnea", "outputs": [{"kind": "value"}],
                                 "build": {"optimization": "O1", "march_native": false}})";

// A CSV trajectory of `knots` random arm7 states (columns q_0.., v_0.., a_0..), and the
// states themselves.
struct Trajectory {
  std::filesystem::path path;
  std::vector<Eigen::VectorXd> q, v, a;
};

Trajectory writeTrajectory(const TempDir& dir, const Model& model, int knots) {
  Trajectory t;
  t.path = dir / "trajectory.csv";
  std::ofstream out(t.path);
  out << "t";
  for (const char* block : {"q", "v", "a"})
    for (int i = 0; i < 7; ++i) out << "," << block << "_" << i;
  out << "\n";
  const FunctionSpec spec = parseFunctionSpec(kRneaValueSpec);
  out.precision(17);
  for (int k = 0; k < knots; ++k) {
    const std::vector<Eigen::VectorXd> in = randomRuntimeInputs(model, spec, 1000 + k);
    t.q.push_back(in[0]);
    t.v.push_back(in[1]);
    t.a.push_back(in[2]);
    out << 0.01 * k;
    for (const Eigen::VectorXd* block : {&in[0], &in[1], &in[2]})
      for (int i = 0; i < 7; ++i) out << "," << (*block)[i];
    out << "\n";
  }
  return t;
}

class Jobs : public ::testing::TestWithParam<std::string> {
 protected:
  static void SetUpTestSuite() { signal(SIGTERM, SIG_IGN); }  // see end_to_end_test.cpp

  void startServer(std::vector<std::string> extra = {}) {
    // Jobs read the example robots and this test's files, and nothing else.
    std::vector<std::string> args = {"--roudi", "external", "--set",
                                     "jobs.data_dirs=" + (sourceDir() / "examples").string() + ":" + dir_.path().string()};
    args.insert(args.end(), extra.begin(), extra.end());
    server_ = std::make_unique<RobodiffdProcess>(dir_ / "cache", dir_ / ("robodiffd-" + std::to_string(++starts_) + ".log"),
                                                 args);
    ASSERT_TRUE(server_->running());
  }

  std::string submit(client::Connection& c, const std::string& kind, const json& params, Status* status = nullptr) {
    rpc::SubmitJobRequest request{kind, params.dump()};
    rpc::SubmitJobReply reply;
    const Status s = c.submitJob(request, reply);
    if (status != nullptr) *status = s;
    else EXPECT_TRUE(s.ok()) << toString(s.code) << ": " << s.message;
    return reply.job_id;
  }

  rpc::JobInfo status(client::Connection& c, const std::string& id) {
    rpc::JobStatusReply reply;
    const Status s = c.jobStatus(rpc::JobStatusRequest{id}, reply);
    EXPECT_TRUE(s.ok()) << s.message;
    return reply.jobs.empty() ? rpc::JobInfo{} : reply.jobs.front();
  }

  // Polls until the job is final (or the time is up); returns its last status.
  rpc::JobInfo waitFinal(client::Connection& c, const std::string& id, seconds limit = seconds(120)) {
    rpc::JobInfo info;
    const auto until = Clock::now() + limit;
    while (Clock::now() < until) {
      info = status(c, id);
      if (rpc::isFinal(info.state)) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return info;
  }

  // The robodiff-worker children of the server that have live children of their own: a
  // job worker while it builds its function (its own worker pool and the compiler). A
  // killed child not yet reaped (state Z) runs nothing and does not count.
  std::vector<pid_t> busyWorkers() const {
    auto parentOf = [](pid_t pid) -> pid_t {
      // A process that exits between open and read makes the read fail with ESRCH,
      // which libstdc++ throws: such a process has no parent to report.
      std::string text;
      try {
        std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
        text.assign(std::istreambuf_iterator<char>(stat), {});
      } catch (const std::ios_base::failure&) {
        return -1;
      }
      const auto close = text.rfind(')');
      if (close == std::string::npos || close + 2 >= text.size() || text[close + 2] == 'Z') return -1;
      return static_cast<pid_t>(std::atol(text.c_str() + close + 4));  // ") S ppid"
    };
    std::vector<pid_t> all;
    if (DIR* d = opendir("/proc")) {
      while (dirent* e = readdir(d))
        if (const pid_t pid = std::atoi(e->d_name); pid > 0) all.push_back(pid);
      closedir(d);
    }
    std::vector<pid_t> busy;
    for (pid_t p : all) {
      if (parentOf(p) != server_->pid()) continue;
      for (pid_t c : all)
        if (parentOf(c) == p) {
          busy.push_back(p);
          break;
        }
    }
    return busy;
  }

  json trajectoryParams(const Trajectory& t, const std::string& out = "out.rdb") const {
    return {{"urdf", (sourceDir() / "examples/robots/arm7.urdf").string()},
            {"spec_json", json::parse(kRneaJacobianSpec)},
            {"data", t.path.string()},
            {"out", out}};
  }

  // The humanoid's ABA Jacobian, compiled: a job that spends seconds building first.
  json slowParams(const Trajectory& t) const {
    return {{"urdf", (sourceDir() / "examples/robots/humanoid.urdf").string()},
            {"floating_base", true},
            {"spec_json",
             json::parse(R"({"function": "aba", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "tau"]}]})")},
            {"data", t.path.string()}};
  }

  std::unique_ptr<client::Connection> connect() { return connectTo(GetParam()); }

  TempDir dir_;
  RoudiProcess& roudi_ = sharedRoudi();
  Model model_ = loadUrdfString(arm7Text(), RootJoint::Fixed, "arm7.urdf");
  std::unique_ptr<RobodiffdProcess> server_;
  int starts_ = 0;
};

TEST_P(Jobs, TrajectoryJobRunsInAWorkerAndPublishesItsResult) {
  startServer();
  auto c = connect();
  const Trajectory t = writeTrajectory(dir_, model_, 300);
  const std::string id = submit(*c, "trajectory", trajectoryParams(t));
  ASSERT_FALSE(id.empty());
  const rpc::JobInfo done = waitFinal(*c, id);
  ASSERT_EQ(done.state, rpc::JobState::Succeeded) << done.error << "\n" << server_->log();
  EXPECT_EQ(done.progress, 1.0);
  EXPECT_FALSE(done.messages.empty());
  EXPECT_EQ(done.kind, "trajectory");

  rpc::JobResultReply result;
  ASSERT_TRUE(c->jobResult(rpc::JobResultRequest{id}, result).ok());
  const json summary = json::parse(result.result_json);
  EXPECT_EQ(summary["knots"], 300);
  EXPECT_EQ(summary["backend"], "compiled");
  EXPECT_EQ(std::filesystem::path(result.result_dir), dir_ / "cache" / "jobs" / id);
  EXPECT_FALSE(std::filesystem::exists(dir_ / "cache" / "jobs" / (id + ".partial")));

  // Every knot's torques and a few knots' Jacobians against core/dynamics and central differences.
  const batch::TrajectoryOutput out = batch::readTrajectoryBinary(std::filesystem::path(result.result_dir) / "out.rdb");
  ASSERT_EQ(out.knots, 300u);
  ASSERT_EQ(out.output_count, 7u + 147u);
  ASSERT_EQ(out.times.size(), 300u);
  const FunctionSpec spec = parseFunctionSpec(kRneaJacobianSpec);
  for (std::uint64_t k = 0; k < out.knots; ++k) {
    const std::vector<Eigen::VectorXd> in = {t.q[k], t.v[k], t.a[k]};
    const Eigen::VectorXd tau = referenceValue(model_, spec, in);
    for (int i = 0; i < 7; ++i) ASSERT_NEAR(out.knot(k)[i], tau[i], 1e-9 * (1 + std::abs(tau[i]))) << "knot " << k;
    if (k % 100 == 0) {
      const Eigen::MatrixXd jac = finiteDifferenceJacobian(model_, spec, in, {"q", "v", "a"});
      for (int r = 0; r < 7; ++r)
        for (int col = 0; col < 21; ++col)
          EXPECT_NEAR(out.knot(k)[7 + r * 21 + col], jac(r, col), 1e-5 * (1 + std::abs(jac(r, col))));
    }
    EXPECT_DOUBLE_EQ(out.times[k], 0.01 * static_cast<double>(k));
  }

  // The cache's index describes it.
  cache::JobIndex index(dir_ / "cache");
  const auto record = index.find(id);
  ASSERT_TRUE(record.has_value());
  EXPECT_EQ(record->state, "SUCCEEDED");
  EXPECT_EQ(record->result_dir, result.result_dir);
  EXPECT_EQ(json::parse(record->result_json)["knots"], 300);
  EXPECT_GE(record->finished_ms, record->started_ms);
  EXPECT_GT(record->started_ms, 0);

  // A restarted server still knows it (from the index).
  EXPECT_EQ(server_->terminate(), 0);
  startServer();
  auto again = connect();
  const rpc::JobInfo remembered = status(*again, id);
  EXPECT_EQ(remembered.state, rpc::JobState::Succeeded);
  rpc::JobResultReply result_again;
  EXPECT_TRUE(again->jobResult(rpc::JobResultRequest{id}, result_again).ok());
  EXPECT_EQ(result_again.result_dir, result.result_dir);
}

TEST_P(Jobs, CancelledJobStopsWithinASecondAndLeavesNothing) {
  startServer();
  auto c = connect();
  const Trajectory t = writeTrajectory(dir_, model_, 10);
  const std::string id = submit(*c, "trajectory", slowParams(t));
  ASSERT_TRUE(waitFor([&] { return status(*c, id).state == rpc::JobState::Running; }, seconds(30)));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // inside its build by now
  ASSERT_FALSE(rpc::isFinal(status(*c, id).state)) << "the job finished before it could be cancelled";

  const auto start = Clock::now();
  rpc::CancelJobReply cancelled;
  ASSERT_TRUE(c->cancelJob(rpc::CancelJobRequest{id}, cancelled).ok());
  const double seconds_taken = std::chrono::duration<double>(Clock::now() - start).count();
  EXPECT_EQ(cancelled.state, rpc::JobState::Cancelled);
  EXPECT_LT(seconds_taken, 1.0);
  EXPECT_TRUE(busyWorkers().empty()) << "a job worker still has children after the cancel";

  EXPECT_FALSE(std::filesystem::exists(dir_ / "cache" / "jobs" / id));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "cache" / "jobs" / (id + ".partial")));
  rpc::JobResultReply result;
  const Status s = c->jobResult(rpc::JobResultRequest{id}, result);
  EXPECT_EQ(s.code, StatusCode::FailedPrecondition) << s.message;
  EXPECT_NE(s.message.find("CANCELLED"), std::string::npos) << s.message;
  EXPECT_EQ(cache::JobIndex(dir_ / "cache").find(id)->state, "CANCELLED");

  // The server goes on running jobs.
  const Trajectory small = writeTrajectory(dir_, model_, 5);
  const std::string next = submit(*c, "trajectory", trajectoryParams(small, "next.csv"));
  EXPECT_EQ(waitFinal(*c, next).state, rpc::JobState::Succeeded);
}

TEST_P(Jobs, WorkerKilledMidJobFailsTheJobCleanly) {
  startServer();
  auto c = connect();
  const Trajectory t = writeTrajectory(dir_, model_, 10);
  const std::string id = submit(*c, "trajectory", slowParams(t));
  std::vector<pid_t> busy;
  ASSERT_TRUE(waitFor([&] { return !(busy = busyWorkers()).empty(); }, seconds(30))) << server_->log();
  ASSERT_EQ(busy.size(), 1u);
  ::kill(busy[0], SIGKILL);

  const rpc::JobInfo done = waitFinal(*c, id, seconds(30));
  EXPECT_EQ(done.state, rpc::JobState::Failed);
  EXPECT_NE(done.error.find("SIGKILL"), std::string::npos) << done.error;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "cache" / "jobs" / (id + ".partial")));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "cache" / "jobs" / id));

  // A replacement worker runs the next job.
  const Trajectory small = writeTrajectory(dir_, model_, 5);
  EXPECT_EQ(waitFinal(*c, submit(*c, "trajectory", trajectoryParams(small))).state, rpc::JobState::Succeeded);
}

TEST_P(Jobs, BadSubmissionsAreRefusedNamingTheProblem) {
  startServer();
  auto c = connect();
  Status s;
  submit(*c, "fly", json::object(), &s);
  EXPECT_EQ(s.code, StatusCode::InvalidArgument);
  EXPECT_NE(s.message.find("unknown job kind 'fly'"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("trajectory"), std::string::npos) << s.message;

  const Trajectory t = writeTrajectory(dir_, model_, 3);
  json params = trajectoryParams(t);
  params.erase("data");
  submit(*c, "trajectory", params, &s);
  EXPECT_EQ(s.code, StatusCode::InvalidArgument);
  EXPECT_NE(s.message.find("\"data\""), std::string::npos) << s.message;

  params = trajectoryParams(t, "../escape.csv");
  submit(*c, "trajectory", params, &s);
  EXPECT_EQ(s.code, StatusCode::InvalidArgument);
  EXPECT_NE(s.message.find("plain file name"), std::string::npos) << s.message;

  rpc::SubmitJobReply reply;
  s = c->submitJob(rpc::SubmitJobRequest{"trajectory", "[1, 2]"}, reply);
  EXPECT_EQ(s.code, StatusCode::InvalidArgument);

  // A data file with a bad row: accepted (the file exists), then failed naming the line.
  std::ofstream(dir_ / "bad.csv") << "q_0,q_1,q_2,q_3,q_4,q_5,q_6,v_0,v_1,v_2,v_3,v_4,v_5,v_6,a_0,a_1,a_2,a_3,a_4,a_5,a_6\n"
                                  << "0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n"
                                  << "0,0,0,x,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n";
  params = trajectoryParams(t);
  params["data"] = (dir_ / "bad.csv").string();
  const std::string id = submit(*c, "trajectory", params);
  const rpc::JobInfo failed = waitFinal(*c, id);
  EXPECT_EQ(failed.state, rpc::JobState::Failed);
  EXPECT_NE(failed.error.find("bad.csv:3"), std::string::npos) << failed.error;
  EXPECT_NE(failed.error.find("q_3"), std::string::npos) << failed.error;
  rpc::JobStatusReply unknown;
  EXPECT_EQ(c->jobStatus(rpc::JobStatusRequest{"job-0000000000000000"}, unknown).code, StatusCode::NotFound);
}

TEST_P(Jobs, AJobACrashedServerLeftRunningIsFailedByTheNext) {
  startServer();
  std::string id;
  {
    auto c = connect();
    const Trajectory t = writeTrajectory(dir_, model_, 10);
    id = submit(*c, "trajectory", slowParams(t));
    ASSERT_TRUE(waitFor([&] { return status(*c, id).state == rpc::JobState::Running; }, seconds(30)));
  }
  server_->kill();  // SIGKILL while idle: its job worker dies with it (PR_SET_PDEATHSIG)
  EXPECT_EQ(cache::JobIndex(dir_ / "cache").find(id)->state, "RUNNING");
  startServer();
  auto c = connect();
  const rpc::JobInfo info = status(*c, id);
  EXPECT_EQ(info.state, rpc::JobState::Failed);
  EXPECT_NE(info.error.find("robodiffd stopped"), std::string::npos) << info.error;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "cache" / "jobs" / (id + ".partial")));
}

// The other two kinds through the server: identification (the physically consistent fit)
// writes a report and a URDF whose bodies are all valid and close to the truth's
// torques; trajectory optimisation writes a trajectory from q0 to qT within the limits.
TEST_P(Jobs, IdentifyAndTrajoptJobs) {
  startServer();
  auto c = connect();
  const Model truth = batch::perturbInertias(model_, 0.2, 5);
  batch::SyntheticOptions synthetic;
  synthetic.samples = 400;
  synthetic.noise = 0.05;
  batch::writeMeasuredSamples(dir_ / "samples.csv", batch::syntheticSamples(truth, synthetic), model_);
  const json identify = {{"urdf", (sourceDir() / "examples/robots/arm7.urdf").string()},
                         {"data", (dir_ / "samples.csv").string()},
                         {"holdout", 0.25},
                         {"physical", true},
                         {"backend", "interpreted"}};
  const std::string id = submit(*c, "identify", identify);
  const rpc::JobInfo done = waitFinal(*c, id);
  ASSERT_EQ(done.state, rpc::JobState::Succeeded) << done.error << "\n" << server_->log();
  rpc::JobResultReply result;
  ASSERT_TRUE(c->jobResult(rpc::JobResultRequest{id}, result).ok());
  const json summary = json::parse(result.result_json);
  EXPECT_EQ(summary["method"], "physical");
  EXPECT_EQ(summary["urdf"], "identified.urdf");
  EXPECT_LT(summary["worst_held_out_rms"].get<double>(), 1.5 * 0.05) << summary.dump();
  const Model identified = loadUrdfFile((std::filesystem::path(result.result_dir) / "identified.urdf").string());
  for (const auto& body : identified.bodies)
    EXPECT_TRUE(batch::checkBodyValidity(body.parameters()).valid);
  EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(result.result_dir) / "identification.json"));

  json trajopt = {{"urdf", (sourceDir() / "examples/robots/arm7.urdf").string()},
                  {"knots", 12},
                  {"duration", 1.0},
                  {"backend", "interpreted"}};
  const Eigen::VectorXd lo = model_.lowerPositionLimit(), hi = model_.upperPositionLimit();
  std::vector<double> qT;
  for (int i = 0; i < model_.nq; ++i) qT.push_back(lo[i] + 0.7 * (hi[i] - lo[i]));
  trajopt["qT"] = qT;
  const std::string topt = submit(*c, "trajopt", trajopt);
  const rpc::JobInfo optimised = waitFinal(*c, topt);
  ASSERT_EQ(optimised.state, rpc::JobState::Succeeded) << optimised.error;
  ASSERT_TRUE(c->jobResult(rpc::JobResultRequest{topt}, result).ok());
  const json topt_summary = json::parse(result.result_json);
  EXPECT_EQ(topt_summary["status"], "Solve_Succeeded");
  EXPECT_LT(topt_summary["cost"]["total"].get<double>(), topt_summary["initial_cost"].get<double>());
  EXPECT_LT(topt_summary["violation"]["position"].get<double>(), 1e-6);
  std::ifstream csv(std::filesystem::path(result.result_dir) / "trajectory.csv");
  int lines = 0;
  for (std::string line; std::getline(csv, line);) ++lines;
  EXPECT_EQ(lines, 1 + 12);

  // A qT outside the limits is refused at submission, naming the joint.
  qT[2] = hi[2] + 1;
  trajopt["qT"] = qT;
  Status s;
  submit(*c, "trajopt", trajopt, &s);
  EXPECT_EQ(s.code, StatusCode::InvalidArgument);
  EXPECT_NE(s.message.find("outside its position limits"), std::string::npos) << s.message;
}

// A job runs as robodiffd's user: its parameters may only name files under jobs.data_dirs
// (and earlier results), and a refusal says nothing about what lies outside.
TEST_P(Jobs, FilesOutsideTheDataDirectoriesAreNeverRead) {
  startServer();
  auto c = connect();
  TempDir outside;
  const std::string secret = "TOP-SECRET-LINE-d41d8cd9";
  std::ofstream(outside / "secret.urdf") << "<robot name=\"" << secret << "\"><link name=\"" << secret << "\"/>\n";
  const Trajectory t = writeTrajectory(dir_, model_, 3);

  auto refusal = [&](const std::string& field, const std::string& path) {
    json params = trajectoryParams(t);
    params.erase(field + "_json");  // "spec" counts only without "spec_json"
    params[field] = path;
    Status s;
    const std::string id = submit(*c, "trajectory", params, &s);
    EXPECT_EQ(s.code, StatusCode::InvalidArgument) << field << " " << path;
    EXPECT_TRUE(id.empty());
    EXPECT_EQ(s.message.find(secret), std::string::npos) << s.message;
    return s.message;
  };
  // A file that exists and one that does not get the same answer, but for the path.
  const std::string existing = refusal("urdf", (outside / "secret.urdf").string());
  const std::string missing = refusal("urdf", (outside / "missing.urdf").string());
  EXPECT_NE(existing.find("outside the directories"), std::string::npos) << existing;
  EXPECT_EQ(existing.substr(existing.find("' is outside")), missing.substr(missing.find("' is outside")));
  EXPECT_NE(refusal("data", "/etc/shadow").find("outside the directories"), std::string::npos);
  EXPECT_NE(refusal("spec", "/proc/self/environ").find("outside the directories"), std::string::npos);

  // Ways around the check: "..", a symbolic link inside pointing out, a relative path.
  refusal("urdf", (dir_.path() / ".." / outside.path().filename() / "secret.urdf").string());
  std::filesystem::create_symlink(outside / "secret.urdf", dir_ / "link.urdf");
  EXPECT_NE(refusal("urdf", (dir_ / "link.urdf").string()).find("outside the directories"), std::string::npos);
  EXPECT_NE(refusal("data", "trajectory.csv").find("absolute path"), std::string::npos);

  // The server still serves a good job after all that.
  const std::string id = submit(*c, "trajectory", trajectoryParams(t));
  EXPECT_EQ(waitFinal(*c, id).state, rpc::JobState::Succeeded);
}

INSTANTIATE_TEST_SUITE_P(Transports, Jobs, ::testing::Values("iceoryx", "dds"),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace robodiff::testing
