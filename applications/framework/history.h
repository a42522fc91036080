#ifndef SPINESIM_COUPLING_HISTORY_H
#define SPINESIM_COUPLING_HISTORY_H

// history.csv: one row per step, columns fixed by the first row. Rewritten atomically
// from memory at every flush (it stays small), so it is always a complete CSV.

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace spinesim::framework {

class History {
 public:
  using Row = std::vector<std::pair<std::string, double>>;

  // Appends a row; the first row fixes the columns, later rows must name the same ones.
  void add(const Row& row);
  // Reads an existing history.csv (restart) so later rows continue it. InvalidInput naming
  // the file and line for a value that is not a number or a row of the wrong length.
  void load(const std::filesystem::path& file);
  // Drops rows whose `column` value exceeds `limit` (rows written after the checkpoint).
  void truncate_after(const std::string& column, double limit);
  std::string csv() const;
  std::size_t size() const { return rows_.size(); }
  const std::vector<std::string>& columns() const { return columns_; }
  double value(std::size_t row, const std::string& column) const;
  // The last row with its column names (empty before the first row).
  Row last_row() const;

 private:
  std::vector<std::string> columns_;
  std::vector<std::vector<double>> rows_;
};

} // namespace spinesim::framework

#endif
