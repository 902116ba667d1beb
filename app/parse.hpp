// Small, strict parsers for comma-separated command-line values; errors name the option.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace pmfrag::app {

/// A user error: printed as one line, exit code 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Parses "a,b,c" into exactly `count` numbers; throws UsageError naming `option` otherwise.
std::vector<double> parse_numbers(const std::string& option, const std::string& text, std::size_t count);
/// Parses "p,q" into two integers.
std::vector<int> parse_ints(const std::string& option, const std::string& text, std::size_t count);

}  // namespace pmfrag::app
