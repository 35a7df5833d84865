#pragma once
// The bad-input corpus (tests/data/bad_input/, README.md there): one file per case, named for
// what is wrong, with a sidecar "<case>.expect" of "key: value" lines ('#' starts a comment):
//   status:  the gRPC status the coordinator answers (INVALID_ARGUMENT, ...; OK when accepted)
//   message: a substring of the error message that names what is wrong (also checked in the CLI's
//            and the in-process readers' messages)
//   file:    "<package path> = <file relative to the case>": an entry of the scene package sent
//   wire:    "none": the case is not sent as a package (only the CLI and client packer see it)
//   rpc, scene, pad_mib, fill, raw, state: see tests/bad_input/bad_input_test.cpp

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace penumbra::bad_input {

inline std::filesystem::path corpus_root() {
  return std::filesystem::path(PENUMBRA_SOURCE_DIR) / "tests" / "data" / "bad_input";
}

inline std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

struct BadInputCase {
  std::filesystem::path path;  // the case file
  std::string name;            // "<folder>/<file>", for messages
  std::multimap<std::string, std::string> keys;

  std::optional<std::string> get(const std::string& key) const {
    auto found = keys.find(key);
    if (found == keys.end()) return std::nullopt;
    return found->second;
  }
  std::string status() const { return get("status").value_or(""); }
  std::string message() const { return get("message").value_or(""); }
  std::string text() const { return read_bytes(path); }
  // The package entries: package path -> bytes of the file named relative to the case.
  std::map<std::string, std::string> package_files() const {
    std::map<std::string, std::string> files;
    auto [begin, end] = keys.equal_range("file");
    for (auto it = begin; it != end; ++it) {
      size_t equals = it->second.find(" = ");
      if (equals == std::string::npos) throw std::runtime_error(name + ": bad file: line");
      files[it->second.substr(0, equals)] =
          read_bytes(path.parent_path() / it->second.substr(equals + 3));
    }
    return files;
  }
};

// Every case of a folder of the corpus (sorted by name); each must have its .expect.
inline std::vector<BadInputCase> load_cases(const std::string& folder) {
  std::vector<BadInputCase> cases;
  for (const auto& entry : std::filesystem::directory_iterator(corpus_root() / folder)) {
    if (!entry.is_regular_file() || entry.path().extension() == ".expect") continue;
    BadInputCase c;
    c.path = entry.path();
    c.name = folder + "/" + entry.path().filename().string();
    std::ifstream expect(entry.path().string() + ".expect");
    if (!expect) throw std::runtime_error(c.name + " has no .expect file");
    std::string line;
    while (std::getline(expect, line)) {
      if (line.empty() || line[0] == '#') continue;
      size_t colon = line.find(": ");
      if (colon == std::string::npos) {
        if (line.back() == ':') c.keys.emplace(line.substr(0, line.size() - 1), "");
        continue;
      }
      c.keys.emplace(line.substr(0, colon), line.substr(colon + 2));
    }
    cases.push_back(std::move(c));
  }
  std::sort(cases.begin(), cases.end(),
            [](const BadInputCase& a, const BadInputCase& b) { return a.name < b.name; });
  return cases;
}

}  // namespace penumbra::bad_input
