// Run-folder output helpers: a log that prints to the terminal and keeps a
// copy in the run folder, and whole-file writes that fail with a clear error.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

namespace centridem {

// Prints lines to a terminal stream (or nowhere) and appends them to a log
// file. `info` goes to the `out` stream, `progress` and `warn` to `err`.
class RunLog {
public:
  RunLog(std::FILE* out, std::FILE* err) : out_(out), err_(err) {}
  ~RunLog();
  RunLog(const RunLog&) = delete;
  RunLog& operator=(const RunLog&) = delete;

  // Opens the log file, truncated (or appended to: a resumed run's log);
  // lines printed before are written to it.
  void open(const std::string& path, bool append = false);
  void info(std::string_view line);
  void progress(std::string_view line);
  void warn(std::string_view line);
  // Only into the log file (the caller prints it to the terminal itself).
  void note(std::string_view line);

private:
  void emit(std::FILE* terminal, std::string_view line);
  std::FILE* out_;
  std::FILE* err_;
  std::FILE* file_ = nullptr;
  std::string pending_; // lines printed before open()
};

// Creates the folder and its parents; throws InputError naming it and the
// reason when it cannot (a file of that name, no permission): exit 2.
void make_directories(const std::string& path);
// Refuses (InputError naming `key`) a path that exists and is not a folder:
// what make_directories would refuse, checked before any work starts.
void check_output_folder(const std::string& path, const std::string& key);
// Writes `content` to `path` (replacing it); throws std::runtime_error.
void write_text_file(const std::string& path, std::string_view content);
// Writes to a temporary file beside `path`, then renames it over `path`, so
// that a reader (ParaView reloading a series) never sees a half-written file.
void replace_text_file(const std::string& path, std::string_view content);

} // namespace centridem
