#include "core/scene/scene_path.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <system_error>

namespace penumbra {

namespace fs = std::filesystem;

std::string normalize_scene_relative_path(const std::string& path) {
  if (path.empty()) throw std::invalid_argument("the file path is empty");
  if (path.find('\0') != std::string::npos)
    throw std::invalid_argument("the file path contains a NUL byte");
  if (path.find('\\') != std::string::npos)
    throw std::invalid_argument("the file path contains a backslash (use '/')");
  fs::path given(path);
  if (given.is_absolute() || given.has_root_directory() || given.has_root_name())
    throw std::invalid_argument("absolute path '" + path +
                                "' (the files a scene names are relative to the scene file)");
  fs::path normal = given.lexically_normal();
  if (normal.empty() || normal == "." || *normal.begin() == "..")
    throw std::invalid_argument("path '" + path + "' leaves the scene's folder");
  // A trailing separator ("meshes/") names a folder, not a file.
  if (!normal.has_filename())
    throw std::invalid_argument("path '" + path + "' names a folder, not a file");
  return normal.generic_string();
}

std::string read_whole_file(const std::string& path, size_t max_bytes, const char* limit_name) {
  std::error_code error;
  fs::file_status status = fs::status(path, error);
  if (error || !fs::exists(status)) throw std::invalid_argument("cannot open '" + path + "'");
  if (!fs::is_regular_file(status))
    throw std::invalid_argument("'" + path + "' is not a regular file");
  uintmax_t size = fs::file_size(path, error);
  if (error) throw std::invalid_argument("cannot read the size of '" + path + "'");
  if (size > max_bytes)
    throw std::invalid_argument("'" + path + "' has " + std::to_string(size) +
                                " bytes, more than the limit " + limit_name + " = " +
                                std::to_string(max_bytes));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument("cannot open '" + path + "'");
  // Read in blocks (a file may change size between the size query and the read).
  std::string bytes;
  bytes.resize(static_cast<size_t>(std::min<uintmax_t>(size, max_bytes)) + 1);
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<size_t>(in.gcount()));
  while (in && bytes.size() <= max_bytes) {
    char block[65536];
    in.read(block, sizeof block);
    bytes.append(block, static_cast<size_t>(in.gcount()));
  }
  if (in.bad()) throw std::invalid_argument("error while reading '" + path + "'");
  if (bytes.size() > max_bytes)
    throw std::invalid_argument("'" + path + "' grew past the limit " + std::string(limit_name) +
                                " while read");
  return bytes;
}

std::string read_file_inside(const std::string& base_dir, const std::string& relative_path,
                             size_t max_bytes) {
  std::error_code error;
  fs::path base = fs::canonical(base_dir.empty() ? fs::path(".") : fs::path(base_dir), error);
  if (error) throw std::invalid_argument("cannot resolve the scene folder '" + base_dir + "'");
  fs::path target = fs::canonical(base / relative_path, error);
  if (error)
    throw std::invalid_argument("cannot open '" + relative_path + "' in '" + base.string() + "'");
  // Compare whole path components, so that /scenes-other is not taken to be inside /scenes.
  auto [base_end, unused] = std::mismatch(base.begin(), base.end(), target.begin(), target.end());
  if (base_end != base.end())
    throw std::invalid_argument("'" + relative_path + "' resolves (through a symlink) to '" +
                                target.string() + "', outside the scene's folder '" +
                                base.string() + "'");
  return read_whole_file(target.string(), max_bytes);
}

}  // namespace penumbra
