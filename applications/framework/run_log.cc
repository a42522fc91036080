#include "applications/framework/run_log.h"

namespace spinesim::framework {

int RunLog::TeeBuffer::overflow(int c) {
  if (c == traits_type::eof())
    return traits_type::not_eof(c);
  if (a)
    a->sputc(static_cast<char>(c));
  if (b)
    b->sputc(static_cast<char>(c));
  // Whole lines reach the terminal and log.txt as they are written: a long step's progress
  // can be followed (tail -f), and a run that is killed keeps its log.
  if (c == '\n')
    sync();
  return c;
}

int RunLog::TeeBuffer::sync() {
  int r = 0;
  if (a)
    r |= a->pubsync();
  if (b)
    r |= b->pubsync();
  return r;
}

RunLog::RunLog(bool is_root, std::ostream& console) : stream_(&buffer_), is_root_(is_root) {
  if (is_root_) {
    buffer_.a = console.rdbuf();
    buffer_.b = &pending_;
  }
}

void RunLog::open_file(const std::string& path, bool append) {
  if (!is_root_)
    return;
  stream_.flush();
  file_.open(path, append ? std::ios::app : std::ios::trunc);
  file_ << pending_.str();
  pending_.str("");
  buffer_.b = file_.rdbuf();
}

} // namespace spinesim::framework
