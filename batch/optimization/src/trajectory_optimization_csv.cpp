// writeTrajectoryCsv: an optimised trajectory's knots as CSV, numbers in their shortest
// round-trip form (std::to_chars), files written whole or not at all.
#include "robodiff/batch/trajectory_optimization_csv.hpp"

#include <charconv>
#include <sstream>

#include "robodiff/batch/atomic_file.hpp"

namespace robodiff::batch {
namespace {

void writeNumber(std::ostream& out, double value) {
  char buffer[32];
  const std::to_chars_result r = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.write(buffer, r.ptr - buffer);
}

}  // namespace

void writeTrajectoryCsv(std::ostream& out, const Trajectory& trajectory, const std::vector<std::string>& joint_names) {
  const Eigen::Index knots = trajectory.q.rows(), nv = trajectory.q.cols();
  if (static_cast<Eigen::Index>(joint_names.size()) != nv)
    throw std::invalid_argument("trajectory CSV: " + std::to_string(joint_names.size()) + " joint names for " +
                                std::to_string(nv) + " columns");
  const Eigen::MatrixXd* blocks[] = {&trajectory.q, &trajectory.v, &trajectory.a, &trajectory.tau};
  const char* prefixes[] = {"q_", "v_", "a_", "tau_"};
  out << "t";
  for (const char* prefix : prefixes)
    for (const std::string& name : joint_names) out << ',' << prefix << name;
  out << '\n';
  for (Eigen::Index k = 0; k < knots; ++k) {
    writeNumber(out, trajectory.time[k]);
    for (const Eigen::MatrixXd* block : blocks)
      for (Eigen::Index i = 0; i < nv; ++i) {
        out << ',';
        writeNumber(out, (*block)(k, i));
      }
    out << '\n';
  }
}

void writeTrajectoryCsvFile(const std::filesystem::path& path, const Trajectory& trajectory,
                            const std::vector<std::string>& joint_names) {
  std::ostringstream text;
  writeTrajectoryCsv(text, trajectory, joint_names);
  AtomicFile file(path);  // all or nothing; AtomicFileError names the path
  file.write(text.str());
  file.commit();
}

}  // namespace robodiff::batch
