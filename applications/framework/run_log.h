#ifndef SPINESIM_COUPLING_RUN_LOG_H
#define SPINESIM_COUPLING_RUN_LOG_H

// The run's log: everything written goes to the terminal and to log.txt, on rank 0 only.

#include <fstream>
#include <memory>
#include <ostream>
#include <streambuf>
#include <string>

namespace spinesim::framework {

class RunLog {
 public:
  RunLog(bool is_root, std::ostream& console);
  // Starts (or, on restart, appends to) the log file.
  void open_file(const std::string& path, bool append);
  std::ostream& stream() { return stream_; }
  template <typename T>
  RunLog& operator<<(const T& value) {
    stream_ << value;
    return *this;
  }
  RunLog& operator<<(std::ostream& (*manip)(std::ostream&)) {
    stream_ << manip;
    return *this;
  }

 private:
  class TeeBuffer : public std::streambuf {
   public:
    std::streambuf* a = nullptr;
    std::streambuf* b = nullptr;

   protected:
    int overflow(int c) override;
    int sync() override;
  };
  TeeBuffer buffer_;
  std::ofstream file_;
  std::ostream stream_;
  bool is_root_;
};

} // namespace spinesim::framework

#endif
