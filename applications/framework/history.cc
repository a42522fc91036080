#include "applications/framework/history.h"

#include "base/exceptions.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace spinesim::framework {

void History::add(const Row& row) {
  if (columns_.empty())
    for (const auto& [name, value] : row)
      columns_.push_back(name);
  if (row.size() != columns_.size())
    throw std::logic_error("history row has " + std::to_string(row.size()) + " columns, expected " +
                           std::to_string(columns_.size()));
  std::vector<double> values;
  for (std::size_t i = 0; i < row.size(); ++i) {
    if (row[i].first != columns_[i])
      throw std::logic_error("history column '" + row[i].first + "' where '" + columns_[i] +
                             "' was expected");
    values.push_back(row[i].second);
  }
  rows_.push_back(std::move(values));
}

void History::load(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string line;
  if (!std::getline(in, line))
    return;
  columns_.clear();
  rows_.clear();
  if (!line.empty() && line.back() == '\r')
    line.pop_back();
  std::stringstream header(line);
  std::string name;
  while (std::getline(header, name, ','))
    columns_.push_back(name);
  const std::string allowed = "the history.csv the run wrote: a header, then rows of " +
                              std::to_string(columns_.size()) + " numbers separated by commas";
  for (unsigned int line_number = 2; std::getline(in, line); ++line_number) {
    const std::string where = file.string() + ":" + std::to_string(line_number);
    if (!line.empty() && line.back() == '\r') // written on another system
      line.pop_back();
    if (!line.empty() && line.back() == ',')
      throw InvalidInput(where, "history row ends with an empty value", allowed);
    std::stringstream ss(line);
    std::string cell;
    std::vector<double> values;
    while (std::getline(ss, cell, ',')) {
      char* end = nullptr;
      const double v = std::strtod(cell.c_str(), &end);
      if (cell.empty() || end != cell.c_str() + cell.size())
        throw InvalidInput(where, "history value '" + cell + "' is not a number", allowed);
      values.push_back(v);
    }
    if (values.size() != columns_.size())
      throw InvalidInput(where,
                         "history row has " + std::to_string(values.size()) + " values for " +
                             std::to_string(columns_.size()) + " columns",
                         allowed);
    rows_.push_back(values);
  }
}

void History::truncate_after(const std::string& column, double limit) {
  const auto it = std::find(columns_.begin(), columns_.end(), column);
  if (it == columns_.end())
    return;
  const std::size_t c = it - columns_.begin();
  rows_.erase(std::remove_if(rows_.begin(), rows_.end(),
                             [&](const std::vector<double>& r) { return r[c] > limit; }),
              rows_.end());
}

double History::value(std::size_t row, const std::string& column) const {
  const auto it = std::find(columns_.begin(), columns_.end(), column);
  if (it == columns_.end())
    throw std::out_of_range("no history column " + column);
  return rows_.at(row)[it - columns_.begin()];
}

History::Row History::last_row() const {
  Row row;
  if (rows_.empty())
    return row;
  for (std::size_t i = 0; i < columns_.size(); ++i)
    row.emplace_back(columns_[i], rows_.back()[i]);
  return row;
}

std::string History::csv() const {
  std::ostringstream out;
  for (std::size_t i = 0; i < columns_.size(); ++i)
    out << (i ? "," : "") << columns_[i];
  // Round-trip precision: a restarted run reads the rows back, and figures taken over the
  // rows (e.g. the largest virial imbalance) must match the uninterrupted run's.
  out << "\n" << std::setprecision(std::numeric_limits<double>::max_digits10);
  for (const auto& row : rows_) {
    for (std::size_t i = 0; i < row.size(); ++i)
      out << (i ? "," : "") << row[i];
    out << "\n";
  }
  return out.str();
}

} // namespace spinesim::framework
