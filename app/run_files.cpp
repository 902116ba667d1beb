#include "run_files.hpp"

#include <fstream>
#include <iterator>

namespace pmfrag::app {

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

}  // namespace pmfrag::app
