// Error types that reach the user. The command-line layer maps InputError to
// exit code 2 and InstabilityError to exit code 3 (see docs/ARCHITECTURE.md).
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

} // namespace centridem
