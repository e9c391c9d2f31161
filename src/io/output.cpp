#include "io/output.hpp"

#include "base/errors.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <stdexcept>

namespace centridem {

namespace fs = std::filesystem;

RunLog::~RunLog() {
  if (file_) std::fclose(file_);
}

void RunLog::open(const std::string& path, bool append) {
  if (file_) std::fclose(file_);
  file_ = std::fopen(path.c_str(), append ? "a" : "w");
  if (!file_)
    throw std::runtime_error(
        fmt::format("cannot write the log {}: {}", path, std::strerror(errno)));
  std::fwrite(pending_.data(), 1, pending_.size(), file_);
  std::fflush(file_);
  pending_.clear();
}

void RunLog::emit(std::FILE* terminal, std::string_view line) {
  if (terminal) {
    std::fwrite(line.data(), 1, line.size(), terminal);
    std::fputc('\n', terminal);
    std::fflush(terminal);
  }
  if (file_) {
    std::fwrite(line.data(), 1, line.size(), file_);
    std::fputc('\n', file_);
    std::fflush(file_);
  } else {
    pending_.append(line);
    pending_ += '\n';
  }
}

void RunLog::info(std::string_view line) {
  emit(out_, line);
}
void RunLog::progress(std::string_view line) {
  emit(err_, line);
}
void RunLog::note(std::string_view line) {
  emit(nullptr, line);
}
void RunLog::warn(std::string_view line) {
  emit(err_, std::string("warning: ") + std::string(line));
}

void make_directories(const std::string& path) {
  std::error_code ec;
  fs::create_directories(path, ec);
  // A folder the user named (--out, --cache, output_dir) or one inside it: a
  // path that cannot be a folder is bad input (exit 2), named with the reason.
  if (ec || !fs::is_directory(path))
    throw InputError("output folder", "\"" + path + "\"",
                     fmt::format("cannot be created ({}): give a folder that can be written",
                                 ec ? ec.message() : "a file of that name exists"));
}

void check_output_folder(const std::string& path, const std::string& key) {
  std::error_code ec;
  if (fs::exists(path, ec) && !fs::is_directory(path, ec))
    throw InputError(key, "\"" + path + "\"",
                     "is a file: give a folder (it is made when it does not exist)");
}

void write_text_file(const std::string& path, std::string_view content) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error(fmt::format("cannot write {}: {}", path, std::strerror(errno)));
  const std::size_t n = std::fwrite(content.data(), 1, content.size(), f);
  const bool ok = n == content.size() && std::fclose(f) == 0;
  if (!ok) throw std::runtime_error(fmt::format("cannot write {}: {}", path, std::strerror(errno)));
}

void replace_text_file(const std::string& path, std::string_view content) {
  const std::string tmp = path + ".tmp";
  write_text_file(tmp, content);
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) throw std::runtime_error(fmt::format("cannot write {}: {}", path, ec.message()));
}

} // namespace centridem
