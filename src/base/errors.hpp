// Error types that reach the user. The command-line layer maps InputError to
// exit code 2, InstabilityError to exit code 3 and Interrupted to 128 + the
// signal (see docs/ARCHITECTURE.md).
#pragma once

#include <stdexcept>
#include <string>

namespace centridem {

// Bad input: a scenario key, a CSV column, a command-line value. The message
// names the key, the offending value and what is allowed.
class InputError : public std::runtime_error {
public:
  InputError(const std::string& key, const std::string& value, const std::string& allowed)
      : std::runtime_error(key + " = " + value + ": " + allowed), key_(key) {}
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
  const std::string& key() const { return key_; }

private:
  std::string key_;
};

// The simulation went unstable (NaN, an overlap larger than the allowed
// fraction of a radius). The message names the particle, the step and the
// likely cause.
class InstabilityError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

// A run stopped on request (SIGINT, SIGTERM) after writing a checkpoint. The
// command-line layer exits with 128 + signal (130 for SIGINT, 143 for
// SIGTERM) and prints how to resume.
class Interrupted : public std::runtime_error {
public:
  Interrupted(int signal, const std::string& message)
      : std::runtime_error(message), signal_(signal) {}
  int signal() const { return signal_; }

private:
  int signal_;
};

} // namespace centridem
