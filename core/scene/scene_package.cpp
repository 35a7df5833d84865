#include "core/scene/scene_package.h"

#include <openssl/evp.h>

#include <array>
#include <memory>
#include <stdexcept>

#include "core/scene/scene_parser.h"

namespace penumbra {

namespace {

// Incremental SHA-256 through OpenSSL's EVP interface.
class Sha256 {
 public:
  Sha256() : context_(EVP_MD_CTX_new(), EVP_MD_CTX_free) {
    if (!context_ || EVP_DigestInit_ex(context_.get(), EVP_sha256(), nullptr) != 1)
      throw std::runtime_error("SHA-256 is unavailable in OpenSSL");
  }
  void update(std::string_view bytes) {
    if (EVP_DigestUpdate(context_.get(), bytes.data(), bytes.size()) != 1)
      throw std::runtime_error("SHA-256 update failed");
  }
  // A length-prefixed piece: 8 bytes little-endian length, then the bytes.
  void update_framed(std::string_view bytes) {
    std::array<char, 8> length{};
    uint64_t n = bytes.size();
    for (char& byte : length) {
      byte = static_cast<char>(n & 0xff);
      n >>= 8;
    }
    update(std::string_view(length.data(), length.size()));
    update(bytes);
  }
  std::string hex_digest() {
    std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
    unsigned int size = 0;
    if (EVP_DigestFinal_ex(context_.get(), digest.data(), &size) != 1)
      throw std::runtime_error("SHA-256 final failed");
    static constexpr char kHex[] = "0123456789abcdef";
    std::string out;
    for (unsigned int i = 0; i < size; ++i) {
      out.push_back(kHex[digest[i] >> 4]);
      out.push_back(kHex[digest[i] & 0xf]);
    }
    return out;
  }

 private:
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> context_;
};

}  // namespace

std::string sha256_hex(std::string_view bytes) {
  Sha256 hash;
  hash.update(bytes);
  return hash.hex_digest();
}

std::string scene_content_hash(std::string_view scene_json,
                               const std::vector<std::pair<std::string, std::string>>& obj_files) {
  Sha256 hash;
  hash.update_framed(scene_json);
  for (const auto& [path, bytes] : obj_files) {
    hash.update_framed(path);
    hash.update_framed(bytes);
  }
  return hash.hex_digest();
}

ScenePackage collect_scene_package(const std::string& path, const SceneLimits& limits) {
  ScenePackage package;
  package.source = path;
  package.scene_json = read_scene_text(path, limits);
  ParsedScene parsed = parse_scene_with_reader(
      package.scene_json, folder_obj_reader(scene_folder(path), limits), path, limits);
  for (auto& [relative, bytes] : parsed.obj_files) package.files[relative] = std::move(bytes);
  return package;
}

Scene parse_scene_package(const ScenePackage& package, const SceneLimits& limits) {
  ObjFileReader from_package = [&package](const std::string& relative) {
    auto found = package.files.find(relative);
    if (found == package.files.end())
      throw std::invalid_argument("'" + relative + "' is not in the scene package");
    return found->second;
  };
  std::string source = package.source.empty() ? std::string("<scene package>") : package.source;
  return parse_scene_with_reader(package.scene_json, from_package, source, limits).scene;
}

}  // namespace penumbra
