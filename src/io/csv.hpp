// Small helpers for the comma-separated files centridem reads (sieve tables,
// shear curves): split a line into trimmed fields, read one field as a finite
// number. Errors are InputError naming `where` (file, line, column) and the
// offending text, so every reader reports bad input the same way.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace centridem {

// `s` without leading and trailing blanks, tabs and carriage returns.
std::string_view trim_blanks(std::string_view s);

// The comma-separated fields of `line`, each trimmed; "" gives one empty field.
std::vector<std::string_view> split_commas(std::string_view line);

// `field` as a finite double (the whole field must be the number); otherwise
// throws InputError(where, "\"field\"", "expected a finite number").
double parse_finite_number(std::string_view field, const std::string& where);

} // namespace centridem
