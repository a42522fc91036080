#ifndef SPINESIM_FEM_HEAT_MESSAGE_FORMAT_H
#define SPINESIM_FEM_HEAT_MESSAGE_FORMAT_H

// Numbers and input slots as the heat solver's messages print them.

#include <sstream>
#include <string>

namespace spinesim::fem {

// v with the stream's default format (six significant digits), e.g. "0.01", "1e-05".
inline std::string format_number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// "<kind> <i+1>": the name of the i-th numbered slot of a kind, e.g. "Heat flux 2".
inline std::string slot_name(const std::string& kind, unsigned int i) {
  return kind + " " + std::to_string(i + 1);
}

} // namespace spinesim::fem

#endif
