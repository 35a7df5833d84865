#include "client/exact_reference_cache.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>

#include "core/exact/exact_reference.h"
#include "core/image/image.h"
#include "penumbra/version.h"

namespace penumbra {

namespace {

// FNV-1a, 64 bits: a stable file name for the cache key.
uint64_t fnv1a(const std::string& text) {
  uint64_t hash = 1469598103934665603ull;
  for (unsigned char c : text) {
    hash ^= c;
    hash *= 1099511628211ull;
  }
  return hash;
}

}  // namespace

std::filesystem::path exact_reference_cache_dir() {
  if (const char* dir = std::getenv("PENUMBRA_CACHE_DIR"); dir && *dir) return dir;
  if (const char* dir = std::getenv("XDG_CACHE_HOME"); dir && *dir)
    return std::filesystem::path(dir) / "penumbra";
  if (const char* home = std::getenv("HOME"); home && *home)
    return std::filesystem::path(home) / ".cache" / "penumbra";
  return std::filesystem::temp_directory_path() / "penumbra-cache";
}

CachedExactReference exact_reference_for(const Scene& scene, const BatchReferenceSpec& reference) {
  const std::string key =
      scene.content_hash + "|" + kBuildFlavour + "|exact+mask|" +
      std::to_string(reference.camera_samples) + "|" + reference.fallback_method + "|" +
      std::to_string(reference.fallback_samples) + "|" + std::to_string(reference.seed);
  char name[64];
  std::snprintf(name, sizeof name, "exact-%016llx.exr", (unsigned long long)fnv1a(key));
  CachedExactReference result;
  result.path = exact_reference_cache_dir() / "references" / name;
  if (std::filesystem::is_regular_file(result.path)) {
    std::ifstream in(result.path, std::ios::binary);
    std::stringstream bytes;
    bytes << in.rdbuf();
    ImageMetadata metadata;
    try {
      decode_exr(bytes.str(), &metadata);
      if (metadata["penumbra:cache_key"] == key) {
        result.exr = bytes.str();
        result.cached = true;
        result.exact_share = std::atof(metadata["penumbra:exact_share"].c_str());
        result.fallback_pixel_share = std::atof(metadata["penumbra:fallback_pixel_share"].c_str());
        return result;
      }
    } catch (const std::exception&) {
      // Unreadable or someone else's: render it again.
    }
  }
  ExactReferenceOptions options;
  options.camera_samples = reference.camera_samples;
  options.shading.fallback_method = reference.fallback_method;
  options.shading.fallback_samples = int(reference.fallback_samples);
  options.seed = reference.seed;
  auto shared = std::make_shared<const Scene>(scene);
  ExactReferenceImage image = render_exact_reference(shared, options);
  ImageMetadata metadata = exact_reference_metadata(scene, options, image);
  metadata["cache_key"] = key;
  result.exr = encode_exact_reference(image, metadata);
  result.compute_seconds = image.compute_seconds;
  const double total = double(image.exact_samples + image.fallback_samples);
  result.exact_share = total > 0 ? double(image.exact_samples) / total : 0;
  result.fallback_pixel_share = image.fallback_pixel_share();
  std::filesystem::create_directories(result.path.parent_path());
  const std::filesystem::path temporary = result.path.string() + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out << result.exr;
    if (!out.flush())
      throw std::runtime_error("cannot write the reference cache " + temporary.string());
  }
  std::filesystem::rename(temporary, result.path);
  return result;
}

}  // namespace penumbra
