#include "run_files.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>

namespace pmfrag::app {

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

double json_number(const std::string& text, const std::string& key) {
  const auto at = text.find("\"" + key + "\":");
  return at == std::string::npos ? NAN : std::strtod(text.c_str() + at + key.size() + 3, nullptr);
}

std::string json_string(const std::string& text, const std::string& key) {
  const auto at = text.find("\"" + key + "\": \"");
  if (at == std::string::npos) return "";
  std::string out;
  for (std::size_t k = at + key.size() + 5; k < text.size() && text[k] != '"'; ++k) {
    if (text[k] == '\\' && k + 1 < text.size()) ++k;
    out += text[k];
  }
  return out;
}

}  // namespace pmfrag::app
