#include "base/exceptions.h"

#include <sstream>

namespace spinesim {

std::string significant(double value, int digits) {
  std::ostringstream s;
  s.precision(digits);
  s << value;
  return s.str();
}

InvalidInput::InvalidInput(std::string where, std::string problem, std::string allowed)
    : std::runtime_error(where + ": " + problem +
                         (allowed.empty() ? "" : " (allowed: " + allowed + ")")),
      where_(std::move(where)), problem_(std::move(problem)), allowed_(std::move(allowed)) {}

NumericalFailure::NumericalFailure(std::string what_failed, std::string location, std::string hint)
    : std::runtime_error(what_failed + " at " + location), what_failed_(std::move(what_failed)),
      location_(std::move(location)), hint_(std::move(hint)) {}

void NumericalFailure::set_step(unsigned int step, double time) {
  if (!has_step_) {
    has_step_ = true;
    step_ = step;
    time_ = time;
  }
}

std::string NumericalFailure::report() const {
  std::ostringstream out;
  out << "numerical failure: " << what_failed_ << "\n  where: " << location_;
  if (has_step_)
    out << "\n  when:  step " << step_ << ", t = " << time_;
  if (!hint_.empty())
    out << "\n  hint:  " << hint_;
  return out.str();
}

} // namespace spinesim
