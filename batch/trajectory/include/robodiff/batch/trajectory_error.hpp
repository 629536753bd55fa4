#pragma once
// A trajectory file (input CSV or JSON, output CSV or binary) that cannot be used. The
// message starts with the file and, where the file has lines, the 1-based line number
// ("traj.csv:17: column q_joint3: 'abc' is not a number"), then the column or JSON path
// and the offending text.

#include <stdexcept>

namespace robodiff::batch {

class TrajectoryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Thrown by the evaluation and the writers when their `cancelled` callback said so; no
// output file is left behind.
class TrajectoryCancelled : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace robodiff::batch
