// The sums file: a JSON header and the whole image's fixed-point sums, zlib-compressed.

#include "core/render/sums_file.h"

#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace penumbra {

namespace {

constexpr char kMagic[8] = {'P', 'N', 'S', 'U', 'M', 'S', '0', '1'};
constexpr uint32_t kMaxHeader = 1u << 20;
// TileAccumulator::deserialize's limit on a rect's pixels.
constexpr int64_t kMaxPixels = int64_t(1) << 26;
// zlib inflates at most about 1032 bytes per input byte.
constexpr uint64_t kMaxRatio = 1100;
// The total of merged passes stays far from uint32's end (the per-pixel counts add up).
constexpr uint64_t kMaxPasses = uint64_t(1) << 31;

// The metadata keys that decide which samples a pass draws: parts of one render agree on them.
constexpr const char* kRenderKeys[] = {"penumbra:method", "penumbra:sampler", "penumbra:seed",
                                       "penumbra:scene_hash"};

template <typename T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

std::string seconds_text(double seconds) {
  std::ostringstream text;
  text.precision(6);
  text << seconds;
  return text.str();
}

}  // namespace

TileAccumulator whole_image_sums(int width, int height, std::span<const TileAccumulator> tiles) {
  // Gathered in TileAccumulator's serialized form (tile.h: its header, then the sums, the
  // squares and the counts, each pixel after pixel), which the final deserialize checks.
  const size_t pixels = size_t(width) * size_t(height);
  std::vector<Fixed128> sums(pixels * 3, 0), squares(pixels * 3, 0);
  std::vector<uint32_t> counts(pixels, 0);
  uint64_t nonfinite = 0;
  for (const TileAccumulator& tile : tiles) {
    const TileRect& r = tile.rect();
    if (r.x0 < 0 || r.y0 < 0 || r.x1 > width || r.y1 > height)
      throw std::invalid_argument("whole_image_sums: a tile lies outside the image");
    const std::string bytes = tile.serialize();
    const size_t n = size_t(r.pixel_count());
    const char* at = bytes.data() + 20;
    uint64_t tile_nonfinite = 0;
    std::memcpy(&tile_nonfinite, at, sizeof tile_nonfinite);
    nonfinite += tile_nonfinite;
    at += sizeof tile_nonfinite;
    const char* tile_sums = at;
    const char* tile_squares = tile_sums + n * 3 * sizeof(Fixed128);
    const char* tile_counts = tile_squares + n * 3 * sizeof(Fixed128);
    for (int y = r.y0; y < r.y1; ++y)
      for (int x = r.x0; x < r.x1; ++x) {
        const size_t from = size_t(y - r.y0) * size_t(r.width()) + size_t(x - r.x0);
        const size_t to = size_t(y) * size_t(width) + size_t(x);
        for (size_t c = 0; c < 3; ++c) {
          Fixed128 value;
          std::memcpy(&value, tile_sums + (from * 3 + c) * sizeof(Fixed128), sizeof value);
          sums[to * 3 + c] += value;
          std::memcpy(&value, tile_squares + (from * 3 + c) * sizeof(Fixed128), sizeof value);
          squares[to * 3 + c] += value;
        }
        uint32_t count;
        std::memcpy(&count, tile_counts + from * sizeof count, sizeof count);
        counts[to] += count;
      }
  }
  std::string whole;
  whole.reserve(28 + pixels * (3 * 16 * 2 + 4));
  put(whole, uint32_t(0x31544e50));  // TileAccumulator's magic number, "PNT1"
  put(whole, int32_t(0));
  put(whole, int32_t(0));
  put(whole, int32_t(width));
  put(whole, int32_t(height));
  put(whole, nonfinite);
  for (const Fixed128& value : sums) put(whole, value);
  for (const Fixed128& value : squares) put(whole, value);
  for (uint32_t count : counts) put(whole, count);
  return TileAccumulator::deserialize(whole);
}

std::string encode_sums(const RenderSums& sums) {
  if (!(sums.sums.rect() == TileRect{0, 0, sums.width, sums.height}))
    throw std::invalid_argument("encode_sums: the sums do not cover the whole image");
  nlohmann::json header = {{"format", kSumsFormat},    {"width", sums.width},
                           {"height", sums.height},    {"first_pass", sums.first_pass},
                           {"passes", sums.passes},    {"compute_seconds", sums.compute_seconds},
                           {"metadata", sums.metadata}};
  const std::string header_text = header.dump();
  const std::string raw = sums.sums.serialize();
  uLongf size = compressBound(uLong(raw.size()));
  std::string body(size, '\0');
  if (compress2(reinterpret_cast<Bytef*>(body.data()), &size,
                reinterpret_cast<const Bytef*>(raw.data()), uLong(raw.size()), 6) != Z_OK)
    throw std::runtime_error("encode_sums: zlib failed");
  body.resize(size);
  std::string out(kMagic, sizeof kMagic);
  put(out, uint32_t(header_text.size()));
  out += header_text;
  put(out, uint64_t(body.size()));
  out += body;
  return out;
}

RenderSums decode_sums(const std::string& bytes, const std::string& name) {
  auto bad = [&](const std::string& what) { return std::invalid_argument(name + ": " + what); };
  std::string_view in(bytes);
  if (in.size() < sizeof kMagic || std::memcmp(in.data(), kMagic, sizeof kMagic) != 0)
    throw bad(std::string("not a sums file (") + kSumsFormat +
              "): it does not start with PNSUMS01");
  in.remove_prefix(sizeof kMagic);
  uint32_t header_size = 0;
  if (in.size() < sizeof header_size) throw bad("truncated before the header's length");
  std::memcpy(&header_size, in.data(), sizeof header_size);
  in.remove_prefix(sizeof header_size);
  if (header_size > kMaxHeader || header_size > in.size())
    throw bad("the header's length " + std::to_string(header_size) + " exceeds the file or 1 MiB");
  nlohmann::json header =
      nlohmann::json::parse(in.substr(0, header_size), nullptr, /*allow_exceptions=*/false);
  in.remove_prefix(header_size);
  if (!header.is_object()) throw bad("the header is not a JSON object");

  RenderSums sums;
  auto field = [&](const char* key) -> const nlohmann::json& {
    auto it = header.find(key);
    if (it == header.end()) throw bad(std::string("header: \"") + key + "\" is missing");
    return *it;
  };
  auto unsigned_field = [&](const char* key, uint64_t max) {
    const nlohmann::json& value = field(key);
    if (!value.is_number_unsigned() || value.get<uint64_t>() > max)
      throw bad(std::string("header: \"") + key + "\" must be an integer in 0.." +
                std::to_string(max));
    return value.get<uint64_t>();
  };
  if (field("format") != kSumsFormat)
    throw bad(std::string("header: \"format\" must be \"") + kSumsFormat + "\"");
  sums.width = int(unsigned_field("width", 1u << 20));
  sums.height = int(unsigned_field("height", 1u << 20));
  if (sums.width < 1 || sums.height < 1 || int64_t(sums.width) * sums.height > kMaxPixels)
    throw bad("header: the image must have 1 to 2^26 pixels");
  sums.passes = uint32_t(unsigned_field("passes", kMaxPasses));
  sums.first_pass = uint32_t(unsigned_field("first_pass", kMaxPasses - sums.passes));
  const nlohmann::json& seconds = field("compute_seconds");
  if (!seconds.is_number() || !(seconds.get<double>() >= 0))
    throw bad("header: \"compute_seconds\" must be a number >= 0");
  sums.compute_seconds = seconds.get<double>();
  const nlohmann::json& metadata = field("metadata");
  if (!metadata.is_object()) throw bad("header: \"metadata\" must be an object");
  for (const auto& [key, value] : metadata.items()) {
    if (!value.is_string()) throw bad("header: metadata \"" + key + "\" must be a string");
    sums.metadata[key] = value.get<std::string>();
  }

  uint64_t body_size = 0;
  if (in.size() < sizeof body_size) throw bad("truncated before the body's length");
  std::memcpy(&body_size, in.data(), sizeof body_size);
  in.remove_prefix(sizeof body_size);
  if (body_size != in.size())
    throw bad("the body's length " + std::to_string(body_size) + " is not the " +
              std::to_string(in.size()) + " bytes that follow");
  const uint64_t raw_size = 28 + uint64_t(sums.width) * uint64_t(sums.height) * (3 * 16 * 2 + 4);
  if (raw_size > body_size * kMaxRatio)
    throw bad("the body (" + std::to_string(body_size) + " bytes) is too short for " +
              std::to_string(sums.width) + "x" + std::to_string(sums.height) + " pixels");
  std::string raw(raw_size, '\0');
  uLongf size = uLongf(raw_size);
  if (uncompress(reinterpret_cast<Bytef*>(raw.data()), &size,
                 reinterpret_cast<const Bytef*>(in.data()), uLong(in.size())) != Z_OK ||
      size != raw_size)
    throw bad("the body is not a zlib stream of " + std::to_string(raw_size) + " bytes");
  try {
    sums.sums = TileAccumulator::deserialize(raw);
  } catch (const std::invalid_argument& error) {
    throw bad(std::string("body: ") + error.what());
  }
  if (!(sums.sums.rect() == TileRect{0, 0, sums.width, sums.height}))
    throw bad("body: the sums' rect is not the whole " + std::to_string(sums.width) + "x" +
              std::to_string(sums.height) + " image");
  const int64_t pixels = int64_t(sums.width) * sums.height;
  for (int64_t i = 0; i < pixels; ++i)
    if (sums.sums.count(i) != sums.passes)
      throw bad("body: pixel (" + std::to_string(i % sums.width) + ", " +
                std::to_string(i / sums.width) + ") has " + std::to_string(sums.sums.count(i)) +
                " samples, the header says " + std::to_string(sums.passes) + " passes");
  return sums;
}

void write_sums(const std::string& path, const RenderSums& sums) {
  const std::string bytes = encode_sums(sums);
  const std::string temporary = path + ".partial";
  {
    std::ofstream file(temporary, std::ios::binary | std::ios::trunc);
    if (!file) throw std::runtime_error(path + ": cannot write");
    file.write(bytes.data(), std::streamsize(bytes.size()));
    if (!file.flush()) throw std::runtime_error(path + ": write failed");
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0)
    throw std::runtime_error(path + ": cannot rename " + temporary + " to it");
}

RenderSums read_sums(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw std::runtime_error(path + ": cannot read");
  std::stringstream bytes;
  bytes << file.rdbuf();
  return decode_sums(bytes.str(), path);
}

RenderSums merge_sums(const std::vector<RenderSums>& parts, const std::vector<std::string>& names) {
  if (parts.empty()) throw std::invalid_argument("merge: no sums to merge");
  if (names.size() != parts.size())
    throw std::invalid_argument("merge: one name per part is needed");
  auto value = [](const RenderSums& part, const char* key) {
    auto it = part.metadata.find(key);
    return it == part.metadata.end() ? std::string("(none)") : it->second;
  };
  const RenderSums& first = parts[0];
  for (size_t i = 1; i < parts.size(); ++i) {
    if (parts[i].width != first.width || parts[i].height != first.height)
      throw std::invalid_argument(names[i] + ": " + std::to_string(parts[i].width) + "x" +
                                  std::to_string(parts[i].height) + " pixels, " + names[0] +
                                  " has " + std::to_string(first.width) + "x" +
                                  std::to_string(first.height));
    for (const char* key : kRenderKeys)
      if (value(parts[i], key) != value(first, key))
        throw std::invalid_argument(names[i] + ": " + key + " is " + value(parts[i], key) + ", " +
                                    names[0] + " has " + value(first, key) +
                                    ": not passes of one render");
  }
  // The ranges, in pass order, must follow one another.
  std::vector<size_t> order(parts.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return parts[a].first_pass < parts[b].first_pass; });
  auto range = [&](size_t i) {
    return "passes " + std::to_string(parts[i].first_pass) + ".." +
           std::to_string(uint64_t(parts[i].first_pass) + parts[i].passes);
  };
  uint64_t total = 0;
  double seconds = 0;
  for (size_t k = 0; k < order.size(); ++k) {
    const RenderSums& part = parts[order[k]];
    if (k > 0) {
      const RenderSums& before = parts[order[k - 1]];
      const uint64_t end = uint64_t(before.first_pass) + before.passes;
      if (part.first_pass < end)
        throw std::invalid_argument(names[order[k]] + " (" + range(order[k]) + ") overlaps " +
                                    names[order[k - 1]] + " (" + range(order[k - 1]) +
                                    "): a pass would count twice");
      if (part.first_pass > end)
        throw std::invalid_argument(names[order[k]] + " (" + range(order[k]) +
                                    ") does not follow " + names[order[k - 1]] + " (" +
                                    range(order[k - 1]) + "): passes " + std::to_string(end) +
                                    ".." + std::to_string(part.first_pass) + " are missing");
    }
    total += part.passes;
    seconds += part.compute_seconds;
  }
  if (total > kMaxPasses) throw std::invalid_argument("merge: more than 2^31 passes");

  RenderSums merged;
  merged.width = first.width;
  merged.height = first.height;
  merged.first_pass = parts[order[0]].first_pass;
  merged.passes = uint32_t(total);
  merged.compute_seconds = seconds;
  merged.metadata = first.metadata;
  merged.metadata.erase("penumbra:interrupted");
  merged.metadata["penumbra:spp"] = std::to_string(total);
  merged.metadata["penumbra:compute_seconds"] = seconds_text(seconds);
  if (merged.first_pass > 0)
    merged.metadata["penumbra:first_pass"] = std::to_string(merged.first_pass);
  else
    merged.metadata.erase("penumbra:first_pass");
  merged.sums = first.sums;
  for (size_t i = 1; i < parts.size(); ++i) merged.sums.merge(parts[i].sums);
  return merged;
}

}  // namespace penumbra
