#include "parse.hpp"

#include <charconv>
#include <cmath>
#include <sstream>

namespace pmfrag::app {

namespace {
std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> parts;
  std::string part;
  std::istringstream in(text);
  while (std::getline(in, part, ',')) parts.push_back(part);
  if (!text.empty() && text.back() == ',') parts.emplace_back();
  return parts;
}

template <class T>
T parse_one(const std::string& option, const std::string& whole, const std::string& s) {
  T value{};
  const char* first = s.data();
  const char* last = s.data() + s.size();
  auto [ptr, ec] = std::from_chars(first, last, value);
  if (s.empty() || ec != std::errc() || ptr != last)
    throw UsageError(option + ": '" + s + "' in '" + whole + "' is not a " +
                     (std::is_integral_v<T> ? "whole number" : "number"));
  if constexpr (std::is_floating_point_v<T>)
    if (!std::isfinite(value)) throw UsageError(option + ": '" + s + "' is not finite");
  return value;
}

template <class T>
std::vector<T> parse_list(const std::string& option, const std::string& text, std::size_t count) {
  const auto parts = split(text);
  if (parts.size() != count)
    throw UsageError(option + ": expected " + std::to_string(count) + " comma-separated values, got '" + text + "'");
  std::vector<T> values;
  for (const auto& s : parts) values.push_back(parse_one<T>(option, text, s));
  return values;
}
}  // namespace

std::vector<double> parse_numbers(const std::string& option, const std::string& text, std::size_t count) {
  return parse_list<double>(option, text, count);
}
std::vector<int> parse_ints(const std::string& option, const std::string& text, std::size_t count) {
  return parse_list<int>(option, text, count);
}

}  // namespace pmfrag::app
