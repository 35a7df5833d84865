#pragma once
// What every client command that loads a scene or takes a reference or an output checks before
// it renders anything: the scene reader's warnings (printed, or refused with --strict), a
// reference EXR of the same scene and resolution, and an output path that can be written.

#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/scene/scene.h"

namespace penumbra {

// Prints the scene reader's warnings to stderr ("penumbra: warning: ..."; the first 20, then a
// count). With `strict`, throws FormatError listing them instead: a typo in a key must not
// change an experiment silently.
void report_scene_warnings(const Scene& scene, bool strict, const std::string& scene_path);

// A reference image checked against the scene it is to judge.
struct CheckedReference {
  Image image;
  // Set when the reference's scene hash differs and the mismatch was accepted: what to print
  // and record (EXR metadata, job status).
  std::vector<std::string> warnings;
};

// The reference EXR's scene (penumbra:scene_hash) and resolution against `scene`: a resolution
// mismatch is always refused; another scene's hash is refused unless `accept_mismatch`, which
// turns it into a warning. Throws std::runtime_error naming the file and both values.
CheckedReference check_reference(const std::string& path, const Scene& scene, bool accept_mismatch);
// The same for reference EXR bytes already in memory (`name` for messages): returns the
// warnings only.
std::vector<std::string> check_reference_bytes(const std::string& bytes, const std::string& name,
                                               const Scene& scene, bool accept_mismatch);

// Refuses an output path that cannot be written before any work is done: a missing or
// unwritable folder, a directory at the path. `extensions` lists the accepted endings (".exr");
// anything else is refused naming them.
void check_output_path(const std::string& path, const std::vector<std::string>& extensions,
                       const std::string& option);

}  // namespace penumbra
