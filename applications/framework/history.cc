#include "applications/framework/history.h"

#include <algorithm>
#include <fstream>
#include <iomanip>
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
  std::stringstream header(line);
  std::string name;
  while (std::getline(header, name, ','))
    columns_.push_back(name);
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string cell;
    std::vector<double> values;
    while (std::getline(ss, cell, ','))
      values.push_back(std::stod(cell));
    if (values.size() == columns_.size())
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

std::string History::csv() const {
  std::ostringstream out;
  for (std::size_t i = 0; i < columns_.size(); ++i)
    out << (i ? "," : "") << columns_[i];
  out << "\n" << std::setprecision(12);
  for (const auto& row : rows_) {
    for (std::size_t i = 0; i < row.size(); ++i)
      out << (i ? "," : "") << row[i];
    out << "\n";
  }
  return out.str();
}

} // namespace spinesim::framework
