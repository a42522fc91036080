#include "base/list_parsing.h"

#include "base/exceptions.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace spinesim {

namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos)
    return "";
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::string::size_type start = 0;
  while (true) {
    const auto end = text.find(separator, start);
    parts.push_back(trim(text.substr(start, end == std::string::npos ? end : end - start)));
    if (end == std::string::npos)
      return parts;
    start = end + 1;
  }
}

double to_number(const std::string& word, const std::string& text, const std::string& where) {
  const char* begin = word.c_str();
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(begin, &end);
  if (word.empty() || end != begin + word.size() || errno == ERANGE || !std::isfinite(value))
    throw InvalidInput(where, "cannot read '" + word + "' in '" + text + "' as a finite number",
                       "comma-separated numbers such as '0, 1.5, -2e-3'");
  return value;
}

} // namespace

std::vector<double> parse_number_list(const std::string& text, const std::string& where,
                                      bool allow_empty) {
  if (trim(text).empty()) {
    if (allow_empty)
      return {};
    throw InvalidInput(where, "is empty", "comma-separated numbers");
  }
  std::vector<double> values;
  for (const auto& word : split(text, ','))
    values.push_back(to_number(word, text, where));
  return values;
}

std::vector<double> parse_numbers(const std::string& text, const std::string& where,
                                  unsigned int count, const std::string& unit) {
  const auto values = parse_number_list(text, where);
  if (values.size() != count)
    throw InvalidInput(where, "has " + std::to_string(values.size()) + " numbers ('" + text + "')",
                       std::to_string(count) + " comma-separated numbers" +
                           (unit.empty() ? "" : " " + unit));
  return values;
}

std::vector<double> parse_point_list(const std::string& text, const std::string& where,
                                     unsigned int dim, unsigned int n_points) {
  std::vector<double> flat;
  unsigned int points = 0;
  for (const auto& point : split(text, ';')) {
    const auto values = parse_number_list(point, where);
    if (values.size() != dim)
      throw InvalidInput(
          where, "point '" + point + "' has " + std::to_string(values.size()) + " coordinates",
          std::to_string(dim) + " comma-separated coordinates per point, points "
                                "separated by ';'");
    flat.insert(flat.end(), values.begin(), values.end());
    ++points;
  }
  if (n_points > 0 && points != n_points)
    throw InvalidInput(where, "has " + std::to_string(points) + " points",
                       std::to_string(n_points) + " points separated by ';'");
  return flat;
}

std::vector<double> parse_crack_corners(const std::string& text, const std::string& where,
                                        unsigned int dim) {
  if (trim(text).empty())
    return {};
  return parse_point_list(text, where, dim, dim == 2 ? 2 : 4);
}

} // namespace spinesim
