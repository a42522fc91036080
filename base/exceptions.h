#ifndef SPINESIM_BASE_EXCEPTIONS_H
#define SPINESIM_BASE_EXCEPTIONS_H

// The two ways a run stops on purpose, shared by every module (base/ is the layer every
// module may use): bad input (exit code 2) and numerical failure (exit code 1).

#include <stdexcept>
#include <string>

namespace spinesim {

// A parameter or input file holds a value the code cannot use. `where` names the file and
// line or the parameter path; `allowed` says what would be accepted.
class InvalidInput : public std::runtime_error {
 public:
  InvalidInput(std::string where, std::string problem, std::string allowed);
  const std::string& where() const { return where_; }
  const std::string& problem() const { return problem_; }
  const std::string& allowed() const { return allowed_; }

 private:
  std::string where_, problem_, allowed_;
};

// A number for a message, to `digits` significant digits (std::to_string's fixed six
// decimals print a residual of 3e-7 as 0.000000).
std::string significant(double value, int digits = 3);

// The numbers went wrong (NaN, divergence, inverted element, singular shape tensor).
// Thrown where it happens, with the step and location known there and a hint for the user.
class NumericalFailure : public std::runtime_error {
 public:
  NumericalFailure(std::string what_failed, std::string location, std::string hint);
  const std::string& what_failed() const { return what_failed_; }
  const std::string& location() const { return location_; }
  const std::string& hint() const { return hint_; }
  // The driver adds the step and simulated time when the exception passes through it.
  void set_step(unsigned int step, double time);
  bool has_step() const { return has_step_; }
  unsigned int step() const { return step_; }
  double time() const { return time_; }
  std::string report() const;
  // Raised on every rank at the same point of the run (base/collective_failure.h, or a check of
  // a value every rank shares): a caller may then undo the attempt and try again without
  // leaving a rank behind. A failure one rank found alone can only end the run.
  void set_collective() { collective_ = true; }
  bool collective() const { return collective_; }

 private:
  std::string what_failed_, location_, hint_;
  bool collective_ = false;
  bool has_step_ = false;
  unsigned int step_ = 0;
  double time_ = 0.0;
};

} // namespace spinesim

#endif
