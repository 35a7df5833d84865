#pragma once
// A whole file read into a string, for the client's commands (probe specs, batch specs,
// reference EXRs).

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace penumbra {

// The file's bytes; throws std::runtime_error "cannot read PATH" when it cannot be opened.
inline std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

}  // namespace penumbra
