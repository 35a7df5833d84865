#include "core/scene/ply_mesh.h"

#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <optional>
#include <stdexcept>

namespace penumbra {

namespace {

enum class PlyFormat { Ascii, BinaryLittleEndian, BinaryBigEndian };
enum class PlyType { Int8, Uint8, Int16, Uint16, Int32, Uint32, Float32, Float64 };

std::optional<PlyType> ply_type(std::string_view name) {
  if (name == "char" || name == "int8") return PlyType::Int8;
  if (name == "uchar" || name == "uint8") return PlyType::Uint8;
  if (name == "short" || name == "int16") return PlyType::Int16;
  if (name == "ushort" || name == "uint16") return PlyType::Uint16;
  if (name == "int" || name == "int32") return PlyType::Int32;
  if (name == "uint" || name == "uint32") return PlyType::Uint32;
  if (name == "float" || name == "float32") return PlyType::Float32;
  if (name == "double" || name == "float64") return PlyType::Float64;
  return std::nullopt;
}

size_t type_size(PlyType type) {
  switch (type) {
    case PlyType::Int8:
    case PlyType::Uint8:
      return 1;
    case PlyType::Int16:
    case PlyType::Uint16:
      return 2;
    case PlyType::Int32:
    case PlyType::Uint32:
    case PlyType::Float32:
      return 4;
    case PlyType::Float64:
      return 8;
  }
  return 1;
}

bool is_integer_type(PlyType type) {
  return type != PlyType::Float32 && type != PlyType::Float64;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::Float32;
  bool is_list = false;
  PlyType count_type = PlyType::Uint8;
  int slot = -1;  // vertex: 0-2 position, 3-5 normal, 6-7 uv; face: 0 the index list
};

struct PlyElement {
  std::string name;
  size_t count = 0;
  std::vector<PlyProperty> properties;
};

// The header, line by line; returns the offset of the first data byte.
size_t parse_header(std::string_view bytes, PlyFormat& format, std::vector<PlyElement>& elements) {
  size_t position = 0;
  int line_number = 0;
  bool have_format = false;
  auto next_line = [&]() -> std::optional<std::string_view> {
    if (position >= bytes.size()) return std::nullopt;
    size_t end = bytes.find('\n', position);
    if (end == std::string_view::npos) end = bytes.size();
    std::string_view line = bytes.substr(position, end - position);
    position = end + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    return line;
  };
  auto fail = [&](const std::string& problem) -> void {
    throw std::invalid_argument("PLY header line " + std::to_string(line_number) + ": " + problem);
  };
  auto words_of = [](std::string_view line) {
    std::vector<std::string_view> words;
    size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
      size_t start = i;
      while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
      if (i > start) words.push_back(line.substr(start, i - start));
    }
    return words;
  };

  std::optional<std::string_view> first = next_line();
  if (!first || *first != "ply") throw std::invalid_argument("not a PLY file (no 'ply' line)");
  while (true) {
    std::optional<std::string_view> line = next_line();
    if (!line) fail("the header has no end_header line");
    std::vector<std::string_view> words = words_of(*line);
    if (words.empty()) continue;
    if (words[0] == "end_header") break;
    if (words[0] == "comment" || words[0] == "obj_info") continue;
    if (words[0] == "format") {
      if (words.size() != 3) fail("format needs a name and a version");
      if (words[1] == "ascii")
        format = PlyFormat::Ascii;
      else if (words[1] == "binary_little_endian")
        format = PlyFormat::BinaryLittleEndian;
      else if (words[1] == "binary_big_endian")
        format = PlyFormat::BinaryBigEndian;
      else
        fail("unknown format '" + std::string(words[1]) + "'");
      if (words[2] != "1.0") fail("unsupported version '" + std::string(words[2]) + "'");
      have_format = true;
    } else if (words[0] == "element") {
      if (words.size() != 3) fail("element needs a name and a count");
      PlyElement element;
      element.name = std::string(words[1]);
      auto [end, error] =
          std::from_chars(words[2].data(), words[2].data() + words[2].size(), element.count);
      if (error != std::errc() || end != words[2].data() + words[2].size())
        fail("element count '" + std::string(words[2]) + "' is not a count");
      elements.push_back(std::move(element));
    } else if (words[0] == "property") {
      if (elements.empty()) fail("property before any element");
      PlyProperty property;
      if (words.size() == 5 && words[1] == "list") {
        std::optional<PlyType> count_type = ply_type(words[2]);
        std::optional<PlyType> item_type = ply_type(words[3]);
        if (!count_type || !item_type) fail("unknown list property type");
        if (!is_integer_type(*count_type)) fail("a list count must have an integer type");
        property.is_list = true;
        property.count_type = *count_type;
        property.type = *item_type;
        property.name = std::string(words[4]);
      } else if (words.size() == 3) {
        std::optional<PlyType> type = ply_type(words[1]);
        if (!type) fail("unknown property type '" + std::string(words[1]) + "'");
        property.type = *type;
        property.name = std::string(words[2]);
      } else {
        fail("malformed property line");
      }
      elements.back().properties.push_back(std::move(property));
    } else {
      fail("unknown header keyword '" + std::string(words[0]) + "'");
    }
  }
  if (!have_format) throw std::invalid_argument("PLY header has no format line");
  return position;
}

// Reads data values one at a time in the file's encoding.
class PlyData {
 public:
  PlyData(std::string_view bytes, size_t start, PlyFormat format)
      : bytes_(bytes), position_(start), format_(format) {}

  double read(PlyType type) {
    if (format_ == PlyFormat::Ascii) return read_ascii(type);
    size_t size = type_size(type);
    if (position_ + size > bytes_.size())
      throw std::invalid_argument(
          "PLY data truncated (the header announces more than the file holds)");
    unsigned char raw[8];
    std::memcpy(raw, bytes_.data() + position_, size);
    position_ += size;
    bool swap =
        (format_ == PlyFormat::BinaryBigEndian) == (std::endian::native == std::endian::little);
    if (swap)
      for (size_t i = 0; i < size / 2; ++i) std::swap(raw[i], raw[size - 1 - i]);
    switch (type) {
      case PlyType::Int8:
        return static_cast<int8_t>(raw[0]);
      case PlyType::Uint8:
        return raw[0];
      case PlyType::Int16:
        return load<int16_t>(raw);
      case PlyType::Uint16:
        return load<uint16_t>(raw);
      case PlyType::Int32:
        return load<int32_t>(raw);
      case PlyType::Uint32:
        return load<uint32_t>(raw);
      case PlyType::Float32:
        return load<float>(raw);
      case PlyType::Float64:
        return load<double>(raw);
    }
    return 0;
  }
  size_t remaining() const { return bytes_.size() - std::min(position_, bytes_.size()); }

 private:
  template <typename T>
  static double load(const unsigned char* raw) {
    T value;
    std::memcpy(&value, raw, sizeof(T));
    return static_cast<double>(value);
  }

  double read_ascii(PlyType type) {
    while (position_ < bytes_.size() && std::strchr(" \t\r\n", bytes_[position_]) &&
           bytes_[position_] != '\0')
      ++position_;
    if (position_ >= bytes_.size())
      throw std::invalid_argument(
          "PLY data truncated (the header announces more than the file holds)");
    size_t start = position_;
    while (position_ < bytes_.size() && !std::strchr(" \t\r\n", bytes_[position_])) ++position_;
    std::string_view word = bytes_.substr(start, position_ - start);
    double value = 0;
    const char* first = word.data();
    if (!word.empty() && *first == '+') ++first;
    auto [end, error] = std::from_chars(first, word.data() + word.size(), value);
    if (error != std::errc() || end != word.data() + word.size())
      throw std::invalid_argument("PLY value '" + std::string(word.substr(0, 32)) +
                                  "' is not a number");
    if (is_integer_type(type) && value != std::floor(value))
      throw std::invalid_argument("PLY value '" + std::string(word.substr(0, 32)) +
                                  "' is not an integer");
    return value;
  }

  std::string_view bytes_;
  size_t position_;
  PlyFormat format_;
};

int vertex_slot(const std::string& name) {
  static const char* const kNames[][2] = {{"x", nullptr},  {"y", nullptr},  {"z", nullptr},
                                          {"nx", nullptr}, {"ny", nullptr}, {"nz", nullptr},
                                          {"u", "s"},      {"v", "t"}};
  for (int slot = 0; slot < 8; ++slot)
    if (name == kNames[slot][0] || (kNames[slot][1] && name == kNames[slot][1])) return slot;
  if (name == "texture_u" || name == "texture_s") return 6;
  if (name == "texture_v" || name == "texture_t") return 7;
  return -1;
}

// The smallest number of bytes one record of `element` can take (lists counted empty).
size_t minimum_record_bytes(const PlyElement& element, PlyFormat format) {
  size_t bytes = 0;
  for (const PlyProperty& property : element.properties)
    bytes += format == PlyFormat::Ascii
                 ? 2
                 : type_size(property.is_list ? property.count_type : property.type);
  return bytes;
}

}  // namespace

PlyReadResult read_ply_mesh(std::string_view bytes, size_t max_vertices, size_t max_faces) {
  PlyFormat format = PlyFormat::Ascii;
  std::vector<PlyElement> elements;
  size_t data_start = parse_header(bytes, format, elements);
  PlyData data(bytes, data_start, format);
  PlyReadResult result;
  TriangleMesh& mesh = result.mesh;
  bool have_vertices = false, have_faces = false;
  size_t vertex_count = 0;

  for (PlyElement& element : elements) {
    size_t minimum = minimum_record_bytes(element, format);
    if (minimum > 0 && element.count > data.remaining() / minimum)
      throw std::invalid_argument("PLY element '" + element.name + "' announces " +
                                  std::to_string(element.count) +
                                  " records, more than the file's bytes can hold");
    if (element.name == "vertex") {
      if (have_vertices) throw std::invalid_argument("PLY file has two vertex elements");
      have_vertices = true;
      if (element.count > max_vertices)
        throw std::invalid_argument("PLY file has " + std::to_string(element.count) +
                                    " vertices, more than the limit " +
                                    std::to_string(max_vertices));
      bool seen[8] = {};
      for (PlyProperty& property : element.properties) {
        property.slot = vertex_slot(property.name);
        if (property.slot >= 0) {
          if (property.is_list)
            throw std::invalid_argument("PLY vertex property '" + property.name + "' is a list");
          if (seen[property.slot])
            throw std::invalid_argument("PLY vertex property '" + property.name + "' repeated");
          seen[property.slot] = true;
        }
      }
      if (!seen[0] || !seen[1] || !seen[2])
        throw std::invalid_argument("PLY vertices need x, y and z properties");
      bool has_normals = seen[3] && seen[4] && seen[5];
      bool has_uvs = seen[6] && seen[7];
      vertex_count = element.count;
      mesh.positions.resize(vertex_count);
      if (has_normals) mesh.normals.resize(vertex_count);
      if (has_uvs) mesh.uvs.resize(vertex_count);
      for (size_t v = 0; v < vertex_count; ++v) {
        double values[8] = {};
        for (const PlyProperty& property : element.properties) {
          if (property.is_list) {
            double count = data.read(property.count_type);
            if (count < 0) throw std::invalid_argument("PLY list with a negative count");
            for (double i = 0; i < count; ++i) data.read(property.type);
            continue;
          }
          double value = data.read(property.type);
          if (property.slot >= 0) values[property.slot] = value;
        }
        for (int k = 0; k < 8; ++k)
          if (!std::isfinite(values[k]))
            throw std::invalid_argument("PLY vertex " + std::to_string(v) +
                                        " has a non-finite value");
        mesh.positions[v] = {values[0], values[1], values[2]};
        if (has_normals) mesh.normals[v] = {values[3], values[4], values[5]};
        if (has_uvs) mesh.uvs[v] = {values[6], values[7]};
      }
    } else if (element.name == "face") {
      if (have_faces) throw std::invalid_argument("PLY file has two face elements");
      have_faces = true;
      if (element.count > max_faces)
        throw std::invalid_argument("PLY file has " + std::to_string(element.count) +
                                    " faces, more than the limit " + std::to_string(max_faces));
      int index_property = -1;
      for (size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        if (property.is_list &&
            (property.name == "vertex_indices" || property.name == "vertex_index")) {
          if (!is_integer_type(property.type))
            throw std::invalid_argument("PLY face indices must have an integer type");
          index_property = int(p);
        }
      }
      if (index_property < 0)
        throw std::invalid_argument("PLY faces need a vertex_indices list property");
      if (!have_vertices)
        throw std::invalid_argument("PLY face element comes before the vertex element");
      mesh.indices.reserve(element.count * 3);
      for (size_t f = 0; f < element.count; ++f) {
        uint32_t corners[4] = {};
        size_t corner_count = 0;
        bool out_of_range = false;
        for (size_t p = 0; p < element.properties.size(); ++p) {
          const PlyProperty& property = element.properties[p];
          if (!property.is_list) {
            data.read(property.type);
            continue;
          }
          double count = data.read(property.count_type);
          if (count < 0) throw std::invalid_argument("PLY list with a negative count");
          for (double i = 0; i < count; ++i) {
            double index = data.read(property.type);
            if (int(p) != index_property) continue;
            // Range-checked before the conversion (an ASCII file may give any number).
            if (!(index >= 0 && index < double(vertex_count)))
              out_of_range = true;
            else if (corner_count < 4)
              corners[corner_count] = static_cast<uint32_t>(index);
            ++corner_count;
          }
        }
        if (out_of_range)
          throw std::invalid_argument("PLY face " + std::to_string(f) +
                                      " has a vertex index outside [0, " +
                                      std::to_string(vertex_count) + ")");
        if (corner_count == 3) {
          mesh.indices.insert(mesh.indices.end(), {corners[0], corners[1], corners[2]});
        } else if (corner_count == 4) {
          mesh.indices.insert(mesh.indices.end(), {corners[0], corners[1], corners[2]});
          mesh.indices.insert(mesh.indices.end(), {corners[0], corners[2], corners[3]});
        } else {
          ++result.skipped_faces;
        }
      }
    } else {
      // Any other element is read past.
      for (size_t r = 0; r < element.count; ++r)
        for (const PlyProperty& property : element.properties) {
          if (!property.is_list) {
            data.read(property.type);
            continue;
          }
          double count = data.read(property.count_type);
          if (count < 0) throw std::invalid_argument("PLY list with a negative count");
          if (format != PlyFormat::Ascii && count * type_size(property.type) > data.remaining())
            throw std::invalid_argument("PLY data truncated");
          for (double i = 0; i < count; ++i) data.read(property.type);
        }
    }
  }
  if (!have_vertices) throw std::invalid_argument("PLY file has no vertex element");
  if (!have_faces) throw std::invalid_argument("PLY file has no face element");
  return result;
}

}  // namespace penumbra
