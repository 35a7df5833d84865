#pragma once
// The rules for files a scene names (SCENE_FORMAT.md: "`obj` paths are relative to the scene file
// and may not leave its folder"), checked twice: lexically on the text of the path (every route,
// including scenes that arrive as packages over the network), and on the filesystem after
// resolving symlinks (only when reading from disk).

#include <string>

namespace penumbra {

// The lexically normal form ("meshes/./a.obj" -> "meshes/a.obj") of a relative path that stays
// inside the scene's folder. Throws std::invalid_argument for an empty, absolute or escaping path
// ("../x.obj", "a/../../x.obj"), a backslash or a NUL byte.
std::string normalize_scene_relative_path(const std::string& path);

// Reads `base_dir`/`relative_path` (already normalized) after checking that the file, with every
// symlink resolved, lies inside the canonical `base_dir` and is a regular file of at most
// `max_bytes`. Throws std::invalid_argument saying which check failed.
std::string read_file_inside(const std::string& base_dir, const std::string& relative_path,
                             size_t max_bytes);

// Reads a whole file of at most `max_bytes` (`limit_name` names that limit in the message).
// Throws std::invalid_argument (missing, unreadable, not a regular file, too large).
std::string read_whole_file(const std::string& path, size_t max_bytes,
                            const char* limit_name = "max_file_bytes");

}  // namespace penumbra
