#include "io/csv.hpp"

#include "base/errors.hpp"

#include <charconv>
#include <cmath>

namespace centridem {

std::string_view trim_blanks(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r'))
    s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> split_commas(std::string_view line) {
  std::vector<std::string_view> out;
  for (;;) {
    const std::size_t c = line.find(',');
    out.push_back(trim_blanks(line.substr(0, c)));
    if (c == std::string_view::npos) break;
    line.remove_prefix(c + 1);
  }
  return out;
}

double parse_finite_number(std::string_view s, const std::string& where) {
  double x = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size() || !std::isfinite(x))
    throw InputError(where, "\"" + std::string(s) + "\"", "expected a finite number");
  return x;
}

} // namespace centridem
