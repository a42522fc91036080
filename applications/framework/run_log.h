#ifndef SPINESIM_COUPLING_RUN_LOG_H
#define SPINESIM_COUPLING_RUN_LOG_H

// The run's log: everything written goes to the terminal and to log.txt, on rank 0 only.
// Until the file is opened, lines are kept in memory and written at the top of the file when
// it opens (a restart opens its log only once the checkpoint has been read: a refused restart
// leaves log.txt as it was).

#include <fstream>
#include <memory>
#include <ostream>
#include <sstream>
#include <streambuf>
#include <string>

namespace spinesim::framework {

class RunLog {
 public:
  RunLog(bool is_root, std::ostream& console);
  // Starts (or, on restart, appends to) the log file, beginning with the lines kept so far.
  void open_file(const std::string& path, bool append);
  bool file_open() const { return file_.is_open(); }
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
  std::stringbuf pending_; // lines written before the file opened
  std::ofstream file_;
  std::ostream stream_;
  bool is_root_;
};

} // namespace spinesim::framework

#endif
